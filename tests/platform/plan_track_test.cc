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

class PlanTrackTest : public testing::TempDirTest {
 protected:
  // A 60 m corridor walk through the synthetic office, and the daemon's configuration
  // for it.
  void Simulate(v1::FloorposedConfig* config, std::string* recording) {
    const FloorPlan plan = testing::SyntheticOffice();
    sim::SimulatorOptions o;
    o.seed = 3;
    o.scenario = sim::Scenario::kCorridor;
    o.target_length_m = 60.0;
    SimulateRecordingResult simulated;
    std::string error;
    *recording = Path("walk.rec");
    ASSERT_TRUE(SimulateToRecording(plan, o, nullptr, {}, *recording, &simulated, &error)) << error;
    config->set_plan_path(Write("office.txt", testing::ThesisText(plan)));
  }
};

TEST_F(PlanTrackTest, RecentPosesAreReprojectedWithEveryNewAlignment) {
  v1::FloorposedConfig config;
  std::string recording, error;
  ASSERT_NO_FATAL_FAILURE(Simulate(&config, &recording));
  config.set_track_history_s(30.0);
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

TEST_F(PlanTrackTest, ReportSplitsThePicksErrorFromTheErrorOnceRegistered) {
  v1::FloorposedConfig config;
  std::string recording, error;
  ASSERT_NO_FATAL_FAILURE(Simulate(&config, &recording));
  EvalReport report;
  ASSERT_TRUE(Evaluate(config, recording, Baseline::kNone, &report, &error)) << error;
  ASSERT_GT(report.accepted, 0u);
  ASSERT_FALSE(report.track.empty());
  EXPECT_EQ(report.pick_error_m, report.track.front().error_m);
  // The first pose under a registered alignment (not merely another version: turning the
  // pick onto the walls' directions makes new versions too), and the errors from there.
  // (Here the daemon registers on the walls scanned before the pick, so that can be the
  // very first pose.)
  size_t first = 0;
  while (first < report.track.size() && !report.track[first].registered) ++first;
  ASSERT_LT(first, report.track.size());
  EXPECT_NEAR(report.first_fix_s,
              static_cast<double>(report.track[first].stamp_ns - report.track[0].stamp_ns) * 1e-9,
              1e-9);
  double sum = 0, max = 0;
  for (size_t i = first; i < report.track.size(); ++i) {
    sum += report.track[i].error_m;
    max = std::max(max, report.track[i].error_m);
  }
  EXPECT_NEAR(report.settled_mean_error_m, sum / static_cast<double>(report.track.size() - first),
              1e-9);
  EXPECT_EQ(report.settled_max_error_m, max);
  EXPECT_LE(report.settled_max_error_m, report.max_error_m);

  // The pick alone never registers: no first fix.
  EvalReport none;
  ASSERT_TRUE(Evaluate(config, recording, Baseline::kNoAlgorithm, &none, &error)) << error;
  EXPECT_EQ(none.first_fix_s, -1.0);
  EXPECT_EQ(none.settled_max_error_m, 0.0);
}

}  // namespace
}  // namespace floorpose::tools
