// The `floorpose` subcommands. Each registers its options on a CLI11 subcommand and
// returns the process exit code when run.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace floorpose::tools {

using Run = std::function<int()>;

// The DEVICE_ID=VALUE pairs of a repeatable option (`--name` of dashboard and cot) into
// `names`; false, with a log line naming `value` ("NAME", "CALLSIGN"), on one that is not.
bool ParseDeviceNames(const std::vector<std::string>& specs, const char* value,
                      std::map<std::string, std::string>* names);

Run AddDemoCommand(CLI::App& app);
Run AddReplayCommand(CLI::App& app);
Run AddRecordCommand(CLI::App& app);
Run AddSimulateCommand(CLI::App& app);
Run AddImportCommand(CLI::App& app);
Run AddImportCarmenCommand(CLI::App& app);
Run AddEvalCommand(CLI::App& app);
Run AddEvalSuiteCommand(CLI::App& app);
Run AddEvalCompareCommand(CLI::App& app);
Run AddBenchCommand(CLI::App& app);
Run AddRouteCommand(CLI::App& app);
Run AddDashboardCommand(CLI::App& app);
Run AddCotCommand(CLI::App& app);
// `floorpose bench daemon` (bench_daemon.cc), a subcommand of `bench`.
Run AddBenchDaemonCommand(CLI::App& bench);
// `floorpose bench route` (route.cc).
Run AddBenchRouteCommand(CLI::App& bench);
// `floorpose bench dashboard` (bench_dashboard.cc).
Run AddBenchDashboardCommand(CLI::App& bench);
// `floorpose bench global` (bench_global.cc).
Run AddBenchGlobalCommand(CLI::App& bench);

// The bundled demo plan and walk: installed beside the binary's prefix, else the source tree.
std::string DefaultDemoDir();
// Its office plan: the benches' default.
inline std::string DefaultDemoPlan() { return DefaultDemoDir() + "/office.geojson"; }

}  // namespace floorpose::tools
