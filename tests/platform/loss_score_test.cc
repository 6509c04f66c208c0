// Scoring after a loss of tracking (issue 43's `relocalize` target): each loss is found
// where the tracker takes one, and scored until it is RELIABLE within 1 m again.
#include <gtest/gtest.h>

#include "platform/floor_plan_io.h"
#include "tests/test_util.h"
#include "tools/lib/evaluation.h"
#include "tools/lib/simulate_recording.h"

namespace floorpose::tools {
namespace {

EvalPose Pose(double t_s, double error_m, bool reliable) {
  EvalPose p;
  p.stamp_ns = static_cast<int64_t>(t_s * 1e9);
  p.error_m = error_m;
  p.reliable = reliable;
  return p;
}

int64_t Ns(double s) { return static_cast<int64_t>(s * 1e9); }

TEST(LossScoreTest, EachLossIsScoredUntilItIsReliableWithinOneMetre) {
  // Poses every second from 10 s to 100 s: losses resume at 20 s and at 70 s.
  // After the first: RELIABLE 3 m off at 22-23 s, RELIABLE within 1 m from 30 s.
  // After the second: never RELIABLE, and the walk ends 30 s later.
  std::vector<EvalPose> track;
  for (int t = 10; t <= 100; ++t) {
    bool reliable = t < 20 || (t >= 22 && t <= 23) || (t >= 30 && t < 70);
    track.push_back(Pose(t, t >= 22 && t <= 23 ? 3.0 : 0.2, reliable));
  }
  const std::vector<LossScore> losses = ScoreLosses(track, {Ns(20), Ns(70)});
  ASSERT_EQ(losses.size(), 2u);
  EXPECT_DOUBLE_EQ(losses[0].resumed_s, 10.0);
  EXPECT_DOUBLE_EQ(losses[0].back_s, 10.0);
  EXPECT_EQ(losses[0].false_reliable, 2u) << "the two poses trusted 3 m off before back";
  EXPECT_DOUBLE_EQ(losses[0].followed_s, 49.0) << "to the last pose before the next loss";
  EXPECT_TRUE(losses[0].timed());
  EXPECT_TRUE(losses[0].back_in_time());
  EXPECT_DOUBLE_EQ(losses[1].back_s, -1.0);
  EXPECT_EQ(losses[1].false_reliable, 0u);
  EXPECT_TRUE(losses[1].timed()) << "followed 30 s";
  EXPECT_FALSE(losses[1].back_in_time());

  // A loss 5 s before the walk ends, never back: too short to tell.
  const std::vector<LossScore> late = ScoreLosses(track, {Ns(95)});
  ASSERT_EQ(late.size(), 1u);
  EXPECT_FALSE(late[0].timed());
  EXPECT_TRUE(ScoreLosses({}, {Ns(20)}).empty());
}

class LossScoreEvalTest : public testing::TempDirTest {};

TEST_F(LossScoreEvalTest, EvaluateFindsTheSimulatedLosses) {
  constexpr const char* kPlanPath = FLOORPOSE_SOURCE_DIR "/tools/demo/office.geojson";
  const FloorPlanParse plan = platform::LoadFloorPlan(kPlanPath);
  ASSERT_TRUE(plan.ok()) << plan.error;
  sim::SimulatorOptions o;
  o.seed = 2;
  o.scenario = sim::Scenario::kRelocalize;
  SimulateRecordingResult simulated;
  std::string error;
  const std::string recording = Path("relocalize.rec");
  ASSERT_TRUE(SimulateToRecording(plan.plan, o, nullptr, {}, recording, &simulated, &error))
      << error;
  const std::vector<sim::Relocalization>& truth = simulated.simulation.relocalizations;
  ASSERT_GE(truth.size(), 2u);

  v1::FloorposedConfig config;
  config.set_plan_path(kPlanPath);
  EvalReport report;
  ASSERT_TRUE(Evaluate(config, recording, Baseline::kNone, &report, &error)) << error;
  ASSERT_FALSE(report.track.empty());
  ASSERT_EQ(report.losses.size(), truth.size());
  const double first_s = static_cast<double>(report.track.front().stamp_ns) * 1e-9;
  for (size_t k = 0; k < truth.size(); ++k) {
    const LossScore& l = report.losses[k];
    EXPECT_NEAR(l.resumed_s, truth[k].found_s - first_s, 1e-6) << "loss " << k;
    // back_s is the first RELIABLE pose within 1 m at or after the loss.
    if (l.back_s < 0) continue;
    for (const EvalPose& p : report.track) {
      const double t = static_cast<double>(p.stamp_ns) * 1e-9 - first_s;
      if (t < l.resumed_s - 1e-9) continue;
      if (p.reliable && p.error_m <= 1.0) {
        EXPECT_NEAR(t - l.resumed_s, l.back_s, 1e-6) << "loss " << k;
        break;
      }
    }
  }
  std::printf("%zu losses; back after", report.losses.size());
  for (const LossScore& l : report.losses) std::printf(" %.1f s", l.back_s);
  std::printf("\n");
}

}  // namespace
}  // namespace floorpose::tools
