// PlanTrack: whenever the alignment changes, the Engine republishes the recent track
// under the new alignment, so maps redraw one consistent trajectory.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>

#include "tests/sim_test_plans.h"
#include "tests/test_util.h"
#include "tools/lib/evaluation.h"
#include "tools/lib/simulate_recording.h"

namespace floorpose::tools {
namespace {

class PlanTrackTest : public testing::TempDirTest {};

TEST_F(PlanTrackTest, RecentPosesAreReprojectedWithEveryNewAlignment) {
  const FloorPlan plan = testing::SyntheticOffice();
  std::string text = std::to_string(plan.segments.size()) + "\n";
  for (const Segment& s : plan.segments)
    text += std::to_string(s.a.x()) + " " + std::to_string(s.a.y()) + " " +
            std::to_string(s.b.x()) + " " + std::to_string(s.b.y()) + "\n";
  const std::string plan_path = Write("office.txt", text);
  sim::SimulatorOptions o;
  o.seed = 3;
  o.scenario = sim::Scenario::kCorridor;
  o.target_length_m = 60.0;
  SimulateRecordingResult simulated;
  std::string error;
  const std::string recording = Path("walk.rec");
  ASSERT_TRUE(SimulateToRecording(plan, o, nullptr, {}, recording, &simulated, &error)) << error;

  v1::FloorposedConfig config;
  config.set_plan_path(plan_path);
  config.mutable_tracking()->set_track_history_s(30.0);
  EvalReport report;
  ASSERT_TRUE(Evaluate(config, recording, Baseline::kNone, &report, &error)) << error;
  ASSERT_GT(report.accepted, 1u);
  // One track per accepted registration, plus the one after the wall pick.
  EXPECT_EQ(report.plan_tracks, report.accepted + 1);

  const v1::PlanTrack& track = report.last_plan_track;
  ASSERT_GT(track.poses_size(), 50);
  // 30 s of poses 0.3 s apart, oldest first, all under the track's alignment.
  const int64_t span =
      track.poses(track.poses_size() - 1).source_stamp_ns() - track.poses(0).source_stamp_ns();
  EXPECT_LE(span, 30'000'000'000);
  EXPECT_GE(span, 25'000'000'000);
  std::map<int64_t, const v1::PlanPose*> published;
  for (const v1::PlanPose& p : report.plan_poses) published[p.source_stamp_ns()] = &p;
  size_t same_version = 0;
  for (int i = 0; i < track.poses_size(); ++i) {
    const v1::PlanPose& p = track.poses(i);
    EXPECT_EQ(p.alignment_version(), track.alignment_version());
    if (i > 0) {
      EXPECT_GT(p.source_stamp_ns(), track.poses(i - 1).source_stamp_ns());
    }
    const auto it = published.find(p.source_stamp_ns());
    ASSERT_NE(it, published.end());
    // Poses first published under this very alignment come back unchanged.
    if (it->second->alignment_version() == track.alignment_version()) {
      ++same_version;
      EXPECT_NEAR(p.x(), it->second->x(), 1e-9);
      EXPECT_NEAR(p.y(), it->second->y(), 1e-9);
    }
    EXPECT_EQ(p.reliability().flag(), it->second->reliability().flag());
  }
  EXPECT_LT(same_version, static_cast<size_t>(track.poses_size()));  // older ones moved
}

}  // namespace
}  // namespace floorpose::tools
