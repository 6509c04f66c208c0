#include "tools/floorpose/eval_real.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "platform/config.h"
#include "platform/floor_plan_io.h"
#include "tools/lib/carmen.h"
#include "tools/lib/evaluation.h"
#include "tools/lib/progress.h"
#include "tools/lib/simulate_recording.h"

namespace floorpose::tools {
namespace {

namespace fs = std::filesystem;

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The configuration every run starts from; only problems are logged (thousands of
// registrations).
bool LoadBaseConfig(const RealSuiteOptions& o, v1::FloorposedConfig* config) {
  spdlog::set_level(spdlog::level::warn);
  std::string error;
  if (!platform::LoadConfig(o.config, config, &error)) {
    spdlog::error("{}", error);
    return false;
  }
  config->set_log_level("warn");
  return true;
}

// results.json (one report a line) and results.md, which is printed too.
void WriteResults(const fs::path& out, const std::vector<EvalReport>& reports,
                  const std::string& md) {
  std::ofstream json(out / "results.json");
  for (const EvalReport& r : reports) json << ToJson(r) << "\n";
  std::ofstream(out / "results.md") << md;
  std::fputs(md.c_str(), stdout);
}

// "12.3%" of a fraction, or "-" when there is nothing to take a share of.
std::string Percent(double part, double whole, int digits = 1) {
  if (!(whole > 0)) return "-";
  char text[32];
  std::snprintf(text, sizeof(text), "%.*f%%", digits, 100.0 * part / whole);
  return text;
}

// ---------------------------------------------------------------------------------------
// CARMEN logs.

struct CarmenRun {
  std::string name, log, gt, odom, plan;  // odom empty: the log has none
  double length_m = 0, duration_s = 0;
  EvalReport report;
  bool ok = false;
};

std::vector<CarmenRun> FindCarmenLogs(const std::string& dir) {
  std::vector<CarmenRun> runs;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string file = e.path().filename().string();
    const std::string suffix = "-corrected.log.gz";
    if (file.size() <= suffix.size() || !file.ends_with(suffix)) continue;
    CarmenRun run;
    run.name = file.substr(0, file.size() - suffix.size());
    run.log = e.path().string();
    run.gt = (fs::path(dir) / (run.name + "_gt.tum")).string();
    run.plan = (fs::path(dir) / (run.name + "_plan.yaml")).string();
    const fs::path odom = fs::path(dir) / (run.name + "_odom.tum");
    if (!fs::exists(run.gt, ec) || !fs::exists(run.plan, ec)) {
      spdlog::warn("{}: no {}_gt.tum or {}_plan.yaml beside it: skipped", run.log, run.name,
                   run.name);
      continue;
    }
    if (fs::exists(odom, ec)) run.odom = odom.string();
    runs.push_back(std::move(run));
  }
  std::sort(runs.begin(), runs.end(),
            [](const CarmenRun& a, const CarmenRun& b) { return a.name < b.name; });
  return runs;
}

// Imports one log as `import-carmen` does and evaluates it; false with a message.
bool EvaluateCarmen(const v1::FloorposedConfig& base, const fs::path& recordings, CarmenRun* run,
                    std::string* error) {
  CarmenLog log;
  std::vector<sim::TimedPose> odom, gt;
  if (!ReadCarmenLog(run->log, &log, error) || !ReadTumTrajectory(run->gt, &gt, error) ||
      (!run->odom.empty() && !ReadTumTrajectory(run->odom, &odom, error)))
    return false;
  CarmenImportOptions options;
  options.name = "carmen " + run->name;
  sim::Simulation walk;
  CarmenImportReport imported;
  // Without odometry the robot moves as the ground truth says: registration is tested on
  // the real scans and the real plan, not against drift.
  if (!CarmenToSimulation(log, run->odom.empty() ? gt : odom, gt, options, &walk, &imported, error))
    return false;
  SimulateRecordingOptions recording;
  recording.odometry = v1::HeadsetPose::WHEEL;
  const std::string path = (recordings / (run->name + ".rec")).string();
  if (!WriteSimulationRecording(walk, run->name + "_plan", "carmen", 0, recording, path, nullptr,
                                error))
    return false;
  v1::FloorposedConfig config = base;
  config.set_plan_path(run->plan);
  if (!Evaluate(config, path, Baseline::kNone, &run->report, error)) return false;
  run->length_m = imported.length_m;
  run->duration_s = imported.duration_s;
  return true;
}

std::string CarmenRow(const CarmenRun& r) {
  const EvalReport& e = r.report;
  const double reliable = e.reliable_fraction * static_cast<double>(e.poses);
  const size_t back = CountLosses(e.losses).back;
  char text[512];
  std::snprintf(text, sizeof(text),
                "| %s | %s | %.0f m, %.0f s%s | %.3f | %.3f | %.2f | %zu | %s | %s | %zu | %zu | "
                "%zu | %.0f | %.1f |",
                r.name.c_str(), r.report.split.c_str(), r.length_m, r.duration_s,
                r.odom.empty() ? " (no odometry)" : "", e.mean_error_m, e.p95_error_m,
                e.max_error_m, e.divergences, Percent(reliable, e.poses).c_str(),
                Percent(e.reliable_precision_1m * reliable, reliable, 2).c_str(),
                e.false_reliable_poses, e.losses.size(), back, e.reg_time_ms_median,
                r.duration_s > 0 ? e.cpu_s / (r.duration_s / 60.0) : 0.0);
  return text;
}

const std::string kCarmenHeader =
    "| log | split | walk | mean m | p95 m | max m | poses > 5 m off | RELIABLE | of those "
    "within 1 m | RELIABLE > 1 m off | losses of tracking | back within " +
    std::to_string(static_cast<int>(kBackAfterLossS)) +
    " s | median update ms | CPU s per minute of log |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";

}  // namespace

int RunCarmenSuite(const RealSuiteOptions& o) {
  v1::FloorposedConfig base;
  if (!LoadBaseConfig(o, &base)) return 2;
  std::vector<CarmenRun> runs = FindCarmenLogs(o.dir);
  if (runs.empty()) {
    spdlog::error("{}: no <name>-corrected.log.gz with <name>_gt.tum and <name>_plan.yaml", o.dir);
    return 2;
  }
  const fs::path recordings = fs::path(o.out) / "recordings";
  fs::create_directories(recordings);
  std::printf("%s", kCarmenHeader.c_str());
  std::fflush(stdout);
  std::mutex mu;
  ParallelFor(runs.size(), o.jobs, "eval-suite --carmen", [&](size_t i, Progress& progress) {
    CarmenRun& run = runs[i];
    std::string error;
    const double cpu0 = ThreadCpuSeconds();
    run.ok = EvaluateCarmen(base, recordings, &run, &error);
    run.report.cpu_s = ThreadCpuSeconds() - cpu0;
    run.report.split = CarmenSplit(run.name);
    run.report.plan_id = run.name;
    std::lock_guard lock(mu);
    progress.Clear();
    if (!run.ok) {
      spdlog::error("{}: {}", run.log, error);
      return;
    }
    std::printf("%s\n", CarmenRow(run).c_str());
    std::fflush(stdout);
  });

  std::ostringstream md;
  std::vector<EvalReport> reports;
  size_t failed = 0;
  for (const char* split : {"development", "validation"}) {
    md << "\n" << (split[0] == 'd' ? "Development" : "Validation") << " logs:\n\n" << kCarmenHeader;
    for (const CarmenRun& r : runs)
      if (r.ok && r.report.split == split) md << CarmenRow(r) << "\n";
  }
  for (const CarmenRun& r : runs) {
    failed += !r.ok;
    if (r.ok) reports.push_back(r.report);
  }
  WriteResults(o.out, reports, md.str());
  return failed ? 1 : 0;
}

// ---------------------------------------------------------------------------------------
// Real walks as waypoints on real plans.

namespace {

struct Floor {
  std::string name, plan_path;
  FloorPlan plan;
  WaypointWalks walks;
};

struct WalkRun {
  const Floor* floor = nullptr;
  std::string walk;
  EvalReport with_pick, without_pick;
  bool ok = false;
};

// Floors: DIR itself or its sub-directories, each with waypoints.csv and a plan (the first
// *.geojson, else geojson_map.json).
std::vector<Floor> FindFloors(const std::string& dir, std::string* error) {
  std::vector<fs::path> dirs;
  std::error_code ec;
  if (fs::exists(fs::path(dir) / "waypoints.csv", ec)) dirs.push_back(dir);
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_directory() && fs::exists(e.path() / "waypoints.csv", ec)) dirs.push_back(e.path());
  std::sort(dirs.begin(), dirs.end());
  std::vector<Floor> floors;
  for (const fs::path& d : dirs) {
    Floor f;
    f.name = WaypointFloorName((d / "waypoints.csv").string());
    for (const auto& e : fs::directory_iterator(d, ec))
      if (e.path().extension() == ".geojson" && (f.plan_path.empty() || e.path() < f.plan_path))
        f.plan_path = e.path().string();
    if (f.plan_path.empty()) f.plan_path = (d / "geojson_map.json").string();
    const FloorPlanParse parse = platform::LoadFloorPlan(f.plan_path);
    if (!parse.ok()) {
      *error = parse.error;
      return {};
    }
    f.plan = parse.plan;
    f.plan.id = f.name;
    if (!ReadWaypoints((d / "waypoints.csv").string(), &f.walks, error)) return {};
    floors.push_back(std::move(f));
  }
  if (floors.empty()) *error = dir + ": no floor (a folder with waypoints.csv and a plan)";
  return floors;
}

bool EvaluateWalk(const v1::FloorposedConfig& base, const fs::path& recordings, WalkRun* run,
                  std::string* error) {
  const Floor& floor = *run->floor;
  const sim::SimulatorOptions sim = WaypointWalkSimulator(run->walk);
  const std::vector<sim::TimedPose> trajectory =
      sim::WalkWaypoints(floor.walks.walks.at(run->walk), sim);
  const std::string path = (recordings / (floor.name + "_" + run->walk + ".rec")).string();
  SimulateRecordingResult simulated;
  if (!SimulateToRecording(floor.plan, sim, &trajectory, {}, path, &simulated, error)) return false;
  v1::FloorposedConfig config = base;
  config.set_plan_path(floor.plan_path);
  if (!Evaluate(config, path, Baseline::kNone, &run->with_pick, error)) return false;
  return Evaluate(config, path, Baseline::kNone, &run->without_pick, error, nullptr,
                  /*no_pick=*/true);
}

// One row over the given runs (with or without the pick).
std::string WalkRow(const std::string& name, const std::string& split, const char* mode,
                    const std::vector<const EvalReport*>& rs) {
  size_t poses = 0, reliable = 0, reliable_ok = 0, false_runs = 0, false_poses = 0;
  size_t placed = 0, diverged = 0;
  double mean = 0, max = 0;
  std::vector<double> p95, first;
  for (const EvalReport* r : rs) {
    poses += r->poses;
    const size_t rel = static_cast<size_t>(std::llround(r->reliable_fraction * r->poses));
    reliable += rel;
    reliable_ok += static_cast<size_t>(std::llround(r->reliable_precision_1m * rel));
    mean += r->mean_error_m * static_cast<double>(r->poses);
    max = std::max(max, r->max_error_m);
    if (r->poses) p95.push_back(r->p95_error_m);  // a walk never placed has none
    false_poses += r->false_reliable_poses;
    false_runs += r->false_reliable_poses > 0;
    diverged += r->divergences > 0;
    const bool ok = r->time_to_first_reliable_s >= 0 && r->first_reliable_error_m <= 1.0;
    placed += ok;
    if (ok) first.push_back(r->time_to_first_reliable_s);
  }
  std::sort(first.begin(), first.end());
  char text[512];
  std::snprintf(
      text, sizeof(text),
      "| %s | %s | %s | %zu | %zu | %.2f | %.2f | %.1f | %zu | %s | %s | %zu (%zu) | %zu "
      "(%s) | %s |",
      name.c_str(), split.c_str(), mode, rs.size(), poses,
      poses ? mean / static_cast<double>(poses) : 0.0, p95.empty() ? 0.0 : Percentile(p95, 0.5),
      max, diverged, Percent(static_cast<double>(reliable), static_cast<double>(poses)).c_str(),
      Percent(static_cast<double>(reliable_ok), static_cast<double>(reliable), 2).c_str(),
      false_poses, false_runs, placed,
      Percent(static_cast<double>(placed), static_cast<double>(rs.size())).c_str(),
      first.empty() ? "-" : (std::to_string(std::lround(Percentile(first, 0.5))) + " s").c_str());
  return text;
}

constexpr char kWalkHeader[] =
    "| floor | split | start | walks | poses | mean m | p95 m (median walk) | max m | walks "
    "> 5 m off | RELIABLE | of those within 1 m | RELIABLE > 1 m off (walks) | first RELIABLE "
    "pose within 1 m (walks) | seconds to it, median |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";

}  // namespace

int RunWaypointSuite(const RealSuiteOptions& o) {
  v1::FloorposedConfig base;
  if (!LoadBaseConfig(o, &base)) return 2;
  std::string error;
  const std::vector<Floor> floors = FindFloors(o.dir, &error);
  if (floors.empty()) {
    spdlog::error("{}", error);
    return 2;
  }
  std::vector<WalkRun> runs;
  for (const Floor& f : floors) {
    size_t taken = 0;
    for (const std::string& id : f.walks.ids)
      if (f.walks.walks.at(id).size() >= 2 && (o.walks == 0 || taken++ < o.walks))
        runs.push_back({&f, id, {}, {}, false});
  }
  const fs::path recordings = fs::path(o.out) / "recordings";
  fs::create_directories(recordings);
  std::mutex mu;
  size_t failed = 0;
  ParallelFor(runs.size(), o.jobs, "eval-suite --waypoints", [&](size_t i, Progress& progress) {
    WalkRun& run = runs[i];
    std::string e;
    run.ok = EvaluateWalk(base, recordings, &run, &e);
    for (EvalReport* r : {&run.with_pick, &run.without_pick}) {
      r->plan_id = run.floor->name;
      r->scenario = run.walk;
      r->split = IlcSplit(run.floor->name);
    }
    run.with_pick.method = "pick";
    run.without_pick.method = "no pick";
    std::lock_guard lock(mu);
    progress.Clear();
    if (!run.ok) {
      ++failed;
      spdlog::error("{} walk {}: {}", run.floor->name, run.walk, e);
      return;
    }
    std::printf(
        "%-3s %s  pick: mean %6.2f m, reliable %3.0f%% (%3.0f%% within 1 m)  no pick: "
        "mean %6.2f m, reliable %3.0f%%\n",
        run.floor->name.c_str(), run.walk.c_str(), run.with_pick.mean_error_m,
        100 * run.with_pick.reliable_fraction, 100 * run.with_pick.reliable_precision_1m,
        run.without_pick.mean_error_m, 100 * run.without_pick.reliable_fraction);
    std::fflush(stdout);
  });

  std::ostringstream md;
  std::vector<EvalReport> reports;
  for (const char* split : {"development", "validation"}) {
    md << "\n" << (split[0] == 'd' ? "Development" : "Validation") << " floors:\n\n" << kWalkHeader;
    for (const bool pick : {true, false}) {
      std::vector<const EvalReport*> all;
      for (const Floor& f : floors) {
        if (std::string(IlcSplit(f.name)) != split) continue;
        std::vector<const EvalReport*> rs;
        for (const WalkRun& r : runs)
          if (r.ok && r.floor == &f) rs.push_back(pick ? &r.with_pick : &r.without_pick);
        all.insert(all.end(), rs.begin(), rs.end());
        md << WalkRow(f.name, split, pick ? "pick" : "no pick", rs) << "\n";
      }
      md << WalkRow("all", split, pick ? "pick" : "no pick", all) << "\n";
    }
  }
  for (const WalkRun& r : runs)
    if (r.ok) reports.push_back(r.with_pick), reports.push_back(r.without_pick);
  WriteResults(o.out, reports, md.str());
  return failed ? 1 : 0;
}

}  // namespace floorpose::tools
