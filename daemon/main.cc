// floorposed: aligns a headset's wall scans to a floor plan and publishes plan poses.
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <iostream>

#include "daemon/daemon.h"
#include "platform/clock.h"
#include "platform/config.h"
#include "platform/logging.h"
#include "platform/systemd.h"
#include "platform/version.h"

int main(int argc, char** argv) {
  using namespace floorpose;
  CLI::App app{"floorposed: indoor positioning of a headset on a floor plan"};
  std::string config_path;
  bool print_config = false;
  std::string plan_override;
  int domain_override = -1;
  std::string device_override;
  app.set_version_flag("--version", std::string("floorposed ") + platform::Version());
  app.add_option("-c,--config", config_path, "configuration file (protobuf text format)");
  app.add_flag("--print-config", print_config, "print the resolved configuration and exit");
  app.add_option("--plan", plan_override, "floor plan to load (overrides plan_path)");
  app.add_option("--domain", domain_override, "DDS domain id (overrides dds.domain_id)");
  app.add_option("--device", device_override, "device id to serve (overrides dds.device_id)");
  CLI11_PARSE(app, argc, argv);

  v1::FloorposedConfig config;
  std::string error;
  if (!platform::LoadConfig(config_path, &config, &error)) {
    std::fprintf(stderr, "floorposed: %s\n", error.c_str());
    return 2;
  }
  if (!plan_override.empty()) config.set_plan_path(plan_override);
  if (domain_override >= 0)
    config.mutable_dds()->set_domain_id(static_cast<uint32_t>(domain_override));
  if (!device_override.empty()) config.mutable_dds()->set_device_id(device_override);
  if (const std::string invalid = platform::ValidateConfig(config); !invalid.empty()) {
    std::fprintf(stderr, "floorposed: %s\n", invalid.c_str());
    return 2;
  }
  if (print_config) {
    std::cout << platform::ResolvedConfigText(config);
    return 0;
  }
  platform::SetUpLogging("floorposed", config.log_level());

  // Signals are taken synchronously by the main thread; the other threads inherit the mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  Daemon daemon(config);
  if (!daemon.Start(&error)) {
    spdlog::critical("cannot start: {}", error);
    return 1;
  }
  platform::NotifyReady();
  const auto watchdog = platform::WatchdogPeriod();
  const auto tick = std::min<std::chrono::microseconds>(watchdog.value_or(std::chrono::seconds(1)),
                                                        std::chrono::seconds(1));
  while (true) {
    timespec timeout{static_cast<time_t>(tick.count() / 1000000),
                     static_cast<long>((tick.count() % 1000000) * 1000)};
    const int sig = sigtimedwait(&signals, nullptr, &timeout);
    if (sig == SIGTERM || sig == SIGINT) {
      spdlog::info("signal {}: stopping", sig);
      break;
    }
    if (sig == SIGHUP) spdlog::info("SIGHUP: nothing to reload; restart to apply a new config");
    // Pet the watchdog only while the io thread is turning: a stuck loop gets restarted.
    const int64_t since_io = platform::MonotonicNs() - daemon.last_io_heartbeat_ns();
    if (watchdog && since_io < 5'000'000'000) platform::NotifyWatchdog();
    platform::NotifyStatus(daemon.StatusLine());
  }
  platform::NotifyStopping();
  daemon.Stop();
  return 0;
}
