// `floorpose import-carmen`: a CARMEN laser log, its odometry and its ground truth as a
// recording for `floorpose eval` and `floorpose replay` (tools/lib/carmen.h).
#include <spdlog/spdlog.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include "tools/floorpose/commands.h"
#include "tools/lib/carmen.h"
#include "tools/lib/progress.h"
#include "tools/lib/simulate_recording.h"

namespace floorpose::tools {
namespace {

struct ImportCarmenOptions {
  std::string log, odom, gt, out, plan_id;
  std::string frame = "unity";
  CarmenImportOptions carmen;
  SimulateRecordingOptions recording;
};

int RunImportCarmen(ImportCarmenOptions o) {
  // Three steps: read the log and the tracks, build the walk, write the recording.
  Progress progress("import-carmen", 3, "steps");
  CarmenLog log;
  std::string error;
  if (!ReadCarmenLog(o.log, &log, &error)) {
    spdlog::error("{}", error);
    return 1;
  }
  std::vector<sim::TimedPose> odom, gt;
  if (!ReadTumTrajectory(o.odom, &odom, &error) || !ReadTumTrajectory(o.gt, &gt, &error)) {
    spdlog::error("{}", error);
    return 1;
  }
  progress.Update(1);
  std::string name = std::filesystem::path(o.log).filename().string();
  for (const char* suffix : {".gz", ".log", "-corrected"})
    if (name.size() > std::strlen(suffix) && name.ends_with(suffix))
      name.resize(name.size() - std::strlen(suffix));
  o.carmen.name = "carmen " + name;
  sim::Simulation walk;
  CarmenImportReport report;
  if (!CarmenToSimulation(log, odom, gt, o.carmen, &walk, &report, &error)) {
    spdlog::error("{}: {}", o.log, error);
    return 1;
  }
  progress.Update(2);
  o.recording.frame = *ParseHeadsetFrame(o.frame);  // checked by CLI11
  o.recording.odometry = v1::HeadsetPose::WHEEL;    // the daemon tracks it as a robot
  size_t records = 0;
  if (!WriteSimulationRecording(walk, o.plan_id.empty() ? name + "_plan" : o.plan_id, "carmen", 0,
                                o.recording, o.out, &records, &error)) {
    spdlog::error("{}", error);
    return 1;
  }
  progress.Update(3);
  progress.Clear();
  std::printf("floorpose import-carmen: %s -> %s\n", o.log.c_str(), o.out.c_str());
  std::printf("  %s\n", walk.description.c_str());
  std::printf("  walk                    %.0f m in %.0f s, %zu poses%s\n", report.length_m,
              report.duration_s, walk.steps.size(),
              report.line_clock ? " (timestamps were line numbers: paced)" : "");
  std::printf("  odometry alone          %.2f m off at the end, %.2f m at most\n",
              report.odom_final_error_m, report.odom_max_error_m);
  std::printf("  recording               %zu records\n", records);
  return 0;
}

}  // namespace

Run AddImportCarmenCommand(CLI::App& app) {
  auto o = std::make_shared<ImportCarmenOptions>();
  app.add_option("--log", o->log, "CARMEN log (FLASER messages), .gz or plain")->required();
  app.add_option("--odom", o->odom, "the robot's odometry, TUM ('timestamp x y z qx qy qz qw')")
      ->required();
  app.add_option("--gt", o->gt, "ground truth, TUM, one pose per FLASER message in log order")
      ->required();
  app.add_option("--out", o->out, "recording file to write")->required();
  app.add_option("--plan-id", o->plan_id, "plan id in the recording (default: <log name>_plan)");
  app.add_option("--period", o->carmen.pose_period_s, "pose period, seconds")
      ->check(CLI::Range(0.01, 10.0))
      ->capture_default_str();
  app.add_option("--pace", o->carmen.pace_mps,
                 "walking speed for logs whose timestamps are line numbers, m/s")
      ->check(CLI::Range(0.05, 10.0))
      ->capture_default_str();
  app.add_option("--max-range", o->carmen.max_range_m,
                 "readings at or over this are 'no return', metres (0: the log's largest)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--device", o->recording.device_id, "envelope device id")->capture_default_str();
  app.add_option("--frame", o->frame, "headset convention: unity (Y up, left-handed) or zup")
      ->check(CLI::IsMember({"unity", "zup"}))
      ->capture_default_str();
  return [o] { return RunImportCarmen(*o); };
}

}  // namespace floorpose::tools
