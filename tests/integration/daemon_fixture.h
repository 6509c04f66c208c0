// The fixture of the tests that run a real floorposed process on a private loopback DDS
// domain and drive it as the HoloLens app would: a small room plan, a walk through it.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "core/sim/demo_walk.h"
#include "floorpose/v1/config.pb.h"
#include "platform/config.h"
#include "platform/dds.h"
#include "platform/floor_plan_io.h"
#include "tests/daemon_test_util.h"
#include "tests/test_util.h"
#include "tools/lib/headset_link.h"
#include "tools/lib/headset_messages.h"
#include "tools/lib/process.h"

namespace floorpose {

namespace fs = std::filesystem;
using platform::Topic;
using std::chrono::seconds;

constexpr HeadsetFrame kFrame = HeadsetFrame::kUnityLeftHandedYUp;

// A 10 m x 6 m room with an inner wall and a pillar, so no direction is unconstrained.
inline const char* kRoomGeoJson = R"({"type": "FeatureCollection", "features": [
  {"type": "Feature", "properties": {"kind": "wall"}, "geometry": {"type": "Polygon",
   "coordinates": [[[0, 0], [10, 0], [10, 6], [0, 6], [0, 0]]]}},
  {"type": "Feature", "properties": {"kind": "wall"}, "geometry": {"type": "LineString",
   "coordinates": [[4, 0], [4, 3.5]]}},
  {"type": "Feature", "properties": {"kind": "wall"}, "geometry": {"type": "Polygon",
   "coordinates": [[[7, 3], [7.5, 3], [7.5, 3.6], [7, 3.6], [7, 3]]]}},
  {"type": "Feature", "properties": {"kind": "door"}, "geometry": {"type": "Point",
   "coordinates": [5, 0]}}]})";

class DaemonTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::TestDirectory();
    fs::create_directories(dir_);
    plan_path_ = (dir_ / "room.geojson").string();
    std::ofstream(plan_path_) << kRoomGeoJson;
    domain_ = testing::UniqueDomain();
  }

  // Writes the configuration, starts floorposed and a headset link to it (with
  // link_security, a secured one).
  void StartDaemon(const std::string& extra_config = "",
                   const platform::DdsSecurity* link_security = nullptr) {
    WriteConfig("hl-test", extra_config, "floorposed.conf");
    LaunchDaemon();
    link_ = std::make_unique<tools::HeadsetLink>(domain_, platform::LoopbackCycloneConfig(),
                                                 "hl-test", link_security);
    ASSERT_TRUE(link_->WaitForDaemon(seconds(15))) << "floorposed did not come up; log in " << dir_;
  }

  // Writes dir_/file: floorposed for `device` on this test's domain and room plan.
  std::string WriteConfig(const std::string& device, const std::string& extra_config,
                          const std::string& file) const {
    const std::string path = (dir_ / file).string();
    std::ofstream(path) << platform::LoopbackDdsConfigText(domain_, device, dds_extra_)
                        << "plan_path: \"" << plan_path_ << "\"\n"
                        << "status_period_s: 0.1\nlog_level: \"debug\"\n"
                        << extra_config;
    return path;
  }

  // Starts floorposed (again, after it stopped or was killed) with the same
  // configuration; each launch logs to its own file (log_path_). The link stays.
  void LaunchDaemon() {
    log_path_ = dir_ / (++launches_ == 1 ? "floorposed.log"
                                         : "floorposed." + std::to_string(launches_) + ".log");
    daemon_ = std::make_unique<tools::ChildProcess>(
        std::vector<std::string>{FLOORPOSED_PATH, "--config", (dir_ / "floorposed.conf").string()},
        log_path_.string());
    ASSERT_TRUE(daemon_->started());
  }

  void TearDown() override {
    if (daemon_ && daemon_->Running()) {
      const auto code = daemon_->Terminate(seconds(2));
      EXPECT_EQ(code, 0) << "floorposed did not stop cleanly within 2 s after SIGTERM";
    }
    // A failed test keeps its directory (configuration, plan, daemon log) to look at.
    std::error_code ignored;
    if (!HasFailure()) fs::remove_all(dir_, ignored);
  }

  // The latest launch's log.
  std::string Log() const {
    std::ifstream in(log_path_);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }

  // Waits for a status that satisfies pred (statuses come every 0.1 s).
  template <typename Pred>
  bool WaitForStatus(Pred pred) {
    return link_->WaitUntil([&] { return link_->status && pred(*link_->status); }, seconds(10));
  }

  // Sends the walk's wall pick (made at step 1), then its meshes and poses paced like a
  // fast replay, so that registrations run while the walk goes on; waits for every
  // plan pose (the first before the rest: HeadsetLink::SendPoseAndAwaitAnswer).
  void PickAndWalk(const sim::DemoWalk& walk) { PickAndWalk(walk, *link_); }
  static void PickAndWalk(const sim::DemoWalk& walk, tools::HeadsetLink& link) {
    link.Send(Topic::kCommand, tools::ToWallPickCommand(walk, kFrame, 1), 0);
    ASSERT_TRUE(link.WaitUntil([&] { return !link.alignments.empty(); }, seconds(10)));
    for (const sim::SimStep& step : walk.steps) {
      for (const sim::SimMesh& m : step.meshes)
        link.Send(Topic::kMeshDelta, tools::ToMeshDelta(m, kFrame, step.stamp_ns), step.stamp_ns);
      const v1::HeadsetPose pose = tools::ToHeadsetPose(step.slam, kFrame, step.stamp_ns);
      if (&step == &walk.steps.front())
        ASSERT_TRUE(link.SendPoseAndAwaitAnswer(pose, step.stamp_ns, seconds(10)))
            << "no answer to the first pose";
      else
        link.Send(Topic::kHeadsetPose, pose, step.stamp_ns);
      link.WaitUntil([] { return false; }, std::chrono::milliseconds(15));
    }
    ASSERT_TRUE(
        link.WaitUntil([&] { return link.plan_poses.size() == walk.steps.size(); }, seconds(10)))
        << link.plan_poses.size() << " of " << walk.steps.size();
  }

  // A walk through the room along `waypoints` (default: a loop through both halves).
  static sim::DemoWalk Walk(double pick_error_m, uint64_t seed,
                            std::vector<Eigen::Vector2d> waypoints = {
                                {1.5, 1.5}, {2.5, 4.8}, {6.0, 4.8}, {8.8, 2.0}, {6, 1.0}}) {
    sim::DemoWalkOptions o;
    o.seed = seed;
    o.heading_drift_rad_per_m = 0;
    o.scale_error = 0;
    o.initial_theta_rad = 0.7;
    o.initial_offset_m = {2.0, -3.0};
    o.pick_point_error_m = pick_error_m;
    o.pick_normal_error_rad = pick_error_m > 0 ? 0.05 : 0.0;
    // The same room the daemon loads.
    const FloorPlanParse plan = platform::ParseGeoJsonFloorPlan(kRoomGeoJson, "room");
    return sim::SimulateDemoWalk(plan.plan, waypoints, o);
  }

  fs::path dir_;
  std::string dds_extra_;  // more of the dds { } block (e.g. security)
  fs::path log_path_;      // of the latest launch
  int launches_ = 0;
  std::string plan_path_;
  uint32_t domain_ = 0;
  std::unique_ptr<tools::ChildProcess> daemon_;
  std::unique_ptr<tools::HeadsetLink> link_;
};

}  // namespace floorpose
