// systemd notify protocol (READY, WATCHDOG, STOPPING, STATUS); no-ops outside systemd.
#pragma once

#include <chrono>
#include <optional>
#include <string>

namespace floorpose::platform {

void NotifyReady();
void NotifyStopping();
void NotifyWatchdog();
void NotifyStatus(const std::string& status);
// Half the watchdog interval systemd asked for, if it asked.
std::optional<std::chrono::microseconds> WatchdogPeriod();

}  // namespace floorpose::platform
