// `floorpose demo`: a real floorposed on a private loopback domain, a simulated walk
// through the bundled office plan with a wall pick, plan poses checked against ground
// truth as they come back.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "core/sim/demo_walk.h"
#include "platform/clock.h"
#include "platform/config.h"
#include "platform/floor_plan_io.h"
#include "tools/floorpose/commands.h"
#include "tools/lib/evaluation.h"
#include "tools/lib/headset_link.h"
#include "tools/lib/headset_messages.h"
#include "tools/lib/process.h"

namespace floorpose::tools {
namespace {

namespace fs = std::filesystem;
using platform::Topic;

}  // namespace

std::string DefaultDemoDir() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec).parent_path();
  const fs::path installed = self / ".." / "share" / "floorpose" / "demo";
  if (fs::exists(installed / "office.geojson", ec)) return installed.string();
  return FLOORPOSE_SOURCE_DEMO_DIR;
}

namespace {

// Waypoints: one "x y" per line, '#' comments.
bool LoadWaypoints(const std::string& path, std::vector<Eigen::Vector2d>* out, std::string* error) {
  std::string text;
  if (!platform::ReadFile(path, 1 << 20, &text, error)) return false;
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    double x, y;
    if (!(ls >> x)) continue;
    if (!(ls >> y) || !std::isfinite(x) || !std::isfinite(y)) {
      *error = path + ":" + std::to_string(n) + ": expected 'x y'";
      return false;
    }
    out->emplace_back(x, y);
  }
  if (out->size() < 2) {
    *error = path + ": a walk needs at least two waypoints";
    return false;
  }
  return true;
}

struct DemoOptions {
  std::string plan;
  std::string walk;
  uint64_t seed = 1;
  double rate = 10.0;
  int domain = -1;
  int every = 5;
  std::string floorposed;
  std::string log;
};

// floorposed's configuration for the demo, written into tmp: loopback DDS on `domain`,
// the plan, and tmp as its state directory. Returns the file.
std::string WriteDemoConfig(const fs::path& tmp, uint32_t domain, const std::string& plan_path) {
  const std::string config_path = (tmp / "floorposed.conf").string();
  std::ofstream conf(config_path);
  conf << platform::LoopbackDdsConfigText(domain, "demo-headset") << "plan_path: \""
       << fs::absolute(plan_path).string() << "\"\n"
       << "log_level: \"info\"\nstate_dir: \"" << tmp.string() << "\"\n";
  return config_path;
}

// The plan poses received, scored against the walk's truth as they come; every `every`th
// printed as a table row.
struct DemoScore {
  std::vector<double> errors;
  size_t reliable = 0, reliable_within_1m = 0;
  size_t printed = 0;

  void Take(const std::vector<v1::PlanPose>& poses, const std::map<int64_t, size_t>& step_of_stamp,
            const sim::DemoWalk& walk, int every) {
    for (; printed < poses.size(); ++printed) {
      const v1::PlanPose& p = poses[printed];
      auto it = step_of_stamp.find(p.source_stamp_ns());
      if (it == step_of_stamp.end()) continue;
      const Pose2& truth = walk.steps[it->second].true_plan;
      const double err = std::hypot(p.x() - truth.position.x(), p.y() - truth.position.y());
      errors.push_back(err);
      const bool is_reliable = p.reliability().flag() == v1::Reliability::RELIABLE;
      reliable += is_reliable;
      reliable_within_1m += is_reliable && err <= 1.0;
      if (printed % static_cast<size_t>(std::max(1, every)) == 0)
        std::printf("%8.1f %8.2f %8.2f  %8.2f %8.2f  %7.3f  %-10s v%lu\n",
                    static_cast<double>(p.source_stamp_ns()) * 1e-9, p.x(), p.y(),
                    truth.position.x(), truth.position.y(), err,
                    v1::Reliability::Flag_Name(p.reliability().flag()).c_str(),
                    static_cast<unsigned long>(p.alignment_version()));
    }
    std::fflush(stdout);
  }
};

// Walks the headset: each step's meshes and pose, at `rate` times real time, the plan
// poses scored as they come; then waits for the last of them and a final status.
void WalkHeadset(const sim::DemoWalk& walk, double pose_period_s, const DemoOptions& o,
                 HeadsetLink& link, DemoScore* score) {
  const HeadsetFrame frame = HeadsetFrame::kUnityLeftHandedYUp;
  std::map<int64_t, size_t> step_of_stamp;
  const auto period = std::chrono::duration<double>(pose_period_s / o.rate);
  auto next = std::chrono::steady_clock::now();
  for (size_t k = 0; k < walk.steps.size(); ++k) {
    const sim::SimStep& step = walk.steps[k];
    for (const sim::SimMesh& m : step.meshes)
      link.Send(Topic::kMeshDelta, ToMeshDelta(m, frame, step.stamp_ns), step.stamp_ns);
    step_of_stamp[step.stamp_ns] = k;
    link.Send(Topic::kHeadsetPose, ToHeadsetPose(step.slam, frame, step.stamp_ns), step.stamp_ns);
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    std::this_thread::sleep_until(next);
    link.Poll();
    score->Take(link.plan_poses, step_of_stamp, walk, o.every);
  }
  link.WaitUntil([&] { return link.plan_poses.size() >= walk.steps.size(); },
                 std::chrono::seconds(5));
  score->Take(link.plan_poses, step_of_stamp, walk, o.every);
  // One more status so the summary has the final counters.
  link.WaitUntil(
      [&] { return link.status && link.status->counters().poses_in() >= walk.steps.size(); },
      std::chrono::seconds(3));
}

// The summary after the walk: poses, errors, the daemon's counters and how it stopped.
void PrintSummary(size_t sent, const HeadsetLink& link, const DemoScore& score,
                  const std::optional<int>& exit_code, const ChildProcess& daemon) {
  const size_t received = link.plan_poses.size();
  const std::vector<double>& errors = score.errors;
  const size_t reliable = score.reliable, reliable_within_1m = score.reliable_within_1m;
  std::printf("\nsummary\n");
  std::printf("  poses sent / plan poses received   %zu / %zu\n", sent, received);
  if (!errors.empty()) {
    std::printf("  error mean / p95 / max             %.3f / %.3f / %.3f m\n", Mean(errors),
                Percentile(errors, 0.95), *std::max_element(errors.begin(), errors.end()));
    std::printf("  final error                        %.3f m\n", errors.back());
    std::printf("  error with the wall pick only      %.3f m (first pose)\n", errors.front());
  }
  if (link.status) {
    const auto& c = link.status->counters();
    std::printf("  registrations run / accepted       %lu / %lu\n",
                static_cast<unsigned long>(c.registrations()),
                static_cast<unsigned long>(c.registrations_accepted()));
    std::printf("  last registration                  %.1f ms, %u points, inlier RMSE %.3f m\n",
                link.status->last_registration().time_ms(),
                link.status->last_registration().points(),
                link.status->last_registration().inlier_rmse_m());
    std::printf("  wall points / live meshes          %lu / %lu\n",
                static_cast<unsigned long>(link.status->wall_points()),
                static_cast<unsigned long>(link.status->live_meshes()));
  }
  std::printf("  flagged reliable                   %.0f%% of poses, %.0f%% of those within 1 m\n",
              received ? 100.0 * reliable / received : 0.0,
              reliable ? 100.0 * reliable_within_1m / reliable : 0.0);
  std::printf("  floorposed stopped                 %s in %ld ms\n",
              exit_code && *exit_code == 0 ? "cleanly" : "NOT cleanly",
              static_cast<long>(daemon.last_stop_time().count()));
}

int RunDemo(const DemoOptions& o) {
  const std::string dir = DefaultDemoDir();
  const std::string plan_path = o.plan.empty() ? dir + "/office.geojson" : o.plan;
  const std::string walk_path = o.walk.empty() ? dir + "/office.walk" : o.walk;
  const FloorPlanParse plan = platform::LoadFloorPlan(plan_path);
  if (!plan.ok()) {
    spdlog::error("{}", plan.error);
    return 1;
  }
  std::vector<Eigen::Vector2d> waypoints;
  std::string error;
  if (!LoadWaypoints(walk_path, &waypoints, &error)) {
    spdlog::error("{}", error);
    return 1;
  }
  sim::DemoWalkOptions walk_options;
  walk_options.seed = o.seed;
  const sim::DemoWalk walk = SimulateDemoWalk(plan.plan, waypoints, walk_options);

  // A private domain: loopback only, an id from our pid so parallel demos stay apart.
  const uint32_t domain =
      o.domain >= 0 ? static_cast<uint32_t>(o.domain) : 100 + static_cast<uint32_t>(getpid() % 120);
  const fs::path tmp = fs::temp_directory_path() / ("floorpose-demo-" + std::to_string(getpid()));
  fs::create_directories(tmp);
  const std::string config_path = WriteDemoConfig(tmp, domain, plan_path);
  const std::string log_path = o.log.empty() ? (tmp / "floorposed.log").string() : o.log;
  const std::string floorposed = o.floorposed.empty() ? FindFloorposed() : o.floorposed;
  std::printf("floorpose demo: plan %s (%zu walls), walk of %.0f m in %zu poses, domain %u\n",
              plan_path.c_str(), plan.plan.segments.size(), walk.length_m, walk.steps.size(),
              domain);
  std::printf("starting %s (log: %s)\n", floorposed.c_str(), log_path.c_str());
  std::fflush(stdout);
  ChildProcess daemon({floorposed, "--config", config_path}, log_path);

  HeadsetLink link(domain, platform::LoopbackCycloneConfig(), "demo-headset");
  if (!link.WaitForDaemon(std::chrono::seconds(15))) {
    spdlog::error("floorposed did not come up on domain {} within 15 s (see {})", domain, log_path);
    return 1;
  }
  const HeadsetFrame frame = HeadsetFrame::kUnityLeftHandedYUp;
  link.Send(Topic::kCommand, ToWallPickCommand(walk, frame, 1), 0);
  if (!link.WaitUntil([&] { return !link.alignments.empty(); }, std::chrono::seconds(5))) {
    spdlog::error("no alignment after the wall pick; daemon said: {}",
                  link.status_messages.empty() ? "nothing" : link.status_messages.back());
    return 1;
  }
  std::printf("wall pick at plan (%.2f, %.2f): alignment version %lu\n", walk.pick.plan_point.x(),
              walk.pick.plan_point.y(),
              static_cast<unsigned long>(link.alignments.back().version()));
  std::printf("%8s %8s %8s  %8s %8s  %7s  %-10s %s\n", "t [s]", "x", "y", "true x", "true y",
              "err [m]", "flag", "alignment");

  DemoScore score;
  WalkHeadset(walk, walk_options.pose_period_s, o, link, &score);
  const auto exit_code = daemon.Terminate(std::chrono::seconds(5));
  PrintSummary(walk.steps.size(), link, score, exit_code, daemon);
  const bool ok = link.plan_poses.size() == walk.steps.size() && exit_code && *exit_code == 0;
  if (!ok) std::printf("demo FAILED: see %s\n", log_path.c_str());
  if (ok && o.log.empty()) fs::remove_all(tmp);
  return ok ? 0 : 1;
}

}  // namespace

Run AddDemoCommand(CLI::App& app) {
  auto o = std::make_shared<DemoOptions>();
  app.add_option("--plan", o->plan, "floor plan (default: the bundled office)");
  app.add_option("--walk", o->walk, "waypoints file, 'x y' per line (default: the bundled walk)");
  app.add_option("--seed", o->seed, "simulation seed")->capture_default_str();
  app.add_option("--rate", o->rate, "playback speed, times real time")->capture_default_str();
  app.add_option("--domain", o->domain, "DDS domain id (default: from the process id)");
  app.add_option("--every", o->every, "print every n-th pose")->capture_default_str();
  app.add_option("--floorposed", o->floorposed, "floorposed binary (default: beside floorpose)");
  app.add_option("--log", o->log, "write floorposed's log here and keep it");
  return [o] { return RunDemo(*o); };
}

}  // namespace floorpose::tools
