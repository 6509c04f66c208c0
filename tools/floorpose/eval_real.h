// `floorpose eval-suite --carmen DIR` and `--waypoints DIR`: the real data in one command.
// CARMEN laser logs with their raster plans (as `import-carmen` then `eval`), and real
// walks given as waypoints on real plans (as `simulate --waypoints` then `eval`, with the
// wall pick and without). One row per log or per floor, development and validation apart
// (tools/lib/evaluation.h), in results.md and results.json under --out.
#pragma once

#include <string>

namespace floorpose::tools {

struct RealSuiteOptions {
  std::string dir;     // the CARMEN directory, or the directory of waypoint floors
  std::string out;     // results.md, results.json, recordings/
  std::string config;  // floorposed configuration (empty: the shipped defaults)
  int jobs = 0;        // parallel runs (0: one per core)
  size_t walks = 0;    // waypoints: the first this many walks of each floor (0: all)
};

int RunCarmenSuite(const RealSuiteOptions& options);
int RunWaypointSuite(const RealSuiteOptions& options);

}  // namespace floorpose::tools
