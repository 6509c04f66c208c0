// Logging set-up: to the journal when started by systemd (JOURNAL_STREAM), else stderr.
#pragma once

#include <string>

namespace floorpose::platform {

// Level: trace, debug, info, warn, error. Returns false on an unknown level (info used).
bool SetUpLogging(const std::string& program, const std::string& level);

}  // namespace floorpose::platform
