// floorpose: the command line of the floorpose project (demo, replay, record, ...).
#include <spdlog/spdlog.h>

#include "platform/logging.h"
#include "platform/version.h"
#include "tools/floorpose/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"floorpose: indoor positioning on floor plans for AR headsets"};
  app.set_version_flag("--version", std::string("floorpose ") + floorpose::platform::Version());
  app.require_subcommand(1);
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn or error");
  std::vector<std::pair<CLI::App*, floorpose::tools::Run>> commands;
  auto add = [&](const char* name, const char* help, auto adder) {
    CLI::App* sub = app.add_subcommand(name, help);
    commands.emplace_back(sub, adder(*sub));
  };
  add("demo", "run floorposed on a bundled floor plan with a simulated walk",
      floorpose::tools::AddDemoCommand);
  add("replay", "publish a recording over DDS", floorpose::tools::AddReplayCommand);
  add("record", "write every floorpose topic to a recording", floorpose::tools::AddRecordCommand);
  add("simulate", "write a simulated walk over a floor plan, with ground truth, as a recording",
      floorpose::tools::AddSimulateCommand);
  add("import", "a CAD or GIS floor plan (DXF, GeoJSON, GeoPackage, Shapefile) as GeoJSON walls",
      floorpose::tools::AddImportCommand);
  add("import-carmen", "a CARMEN laser log with odometry and ground truth as a recording",
      floorpose::tools::AddImportCarmenCommand);
  add("eval", "run a recording through the daemon's code and score it against ground truth",
      floorpose::tools::AddEvalCommand);
  add("eval-suite", "every plan x scenario x seed x method, as a table",
      floorpose::tools::AddEvalSuiteCommand);
  add("eval-compare", "two eval-suite runs of the same walks: the differences, with 95% intervals",
      floorpose::tools::AddEvalCompareCommand);
  add("route", "the shortest route a wearer can walk between two points of a floor plan",
      floorpose::tools::AddRouteCommand);
  add("dashboard", "serve a live map of every wearer to browsers on the local network",
      floorpose::tools::AddDashboardCommand);
  add("cot", "send every wearer and marker to ATAK / TAK as Cursor-on-Target",
      floorpose::tools::AddCotCommand);
  add("bench", "time the registration methods and the closest-wall index",
      floorpose::tools::AddBenchCommand);
  CLI11_PARSE(app, argc, argv);
  floorpose::platform::SetUpLogging("floorpose", log_level);
  for (auto& [sub, run] : commands)
    if (sub->parsed()) return run();
  return 2;
}
