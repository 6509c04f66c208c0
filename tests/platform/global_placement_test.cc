// No wall pick: the daemon's code (Evaluate, as floorposed runs it) places the wearer by
// searching the whole plan, and the belief's updates after it track as after a pick.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "platform/floor_plan_io.h"
#include "tests/test_util.h"
#include "tools/lib/evaluation.h"
#include "tools/lib/simulate_recording.h"

namespace floorpose::tools {
namespace {

class GlobalPlacementTest : public testing::TempDirTest {
 protected:
  static constexpr const char* kPlanPath = FLOORPOSE_SOURCE_DIR "/tools/demo/office.geojson";
  // The office walk of seed 1 on the bundled plan, written to `name` in the test's dir.
  std::string SimulateOffice(sim::SimulatorOptions o, const std::string& name,
                             SimulateRecordingResult* simulated) {
    const FloorPlanParse plan = platform::LoadFloorPlan(kPlanPath);
    EXPECT_TRUE(plan.ok()) << plan.error;
    o.seed = 1;
    o.scenario = sim::Scenario::kOffice;
    std::string error;
    const std::string recording = Path(name);
    EXPECT_TRUE(SimulateToRecording(plan.plan, o, nullptr, {}, recording, simulated, &error))
        << error;
    return recording;
  }
  // The recording evaluated as floorposed runs it with `config` on the office plan, without a
  // pick.
  EvalReport EvaluateWithoutPick(v1::FloorposedConfig config, const std::string& recording) {
    config.set_plan_path(kPlanPath);
    EvalReport report;
    std::string error;
    EXPECT_TRUE(Evaluate(config, recording, Baseline::kNone, &report, &error, nullptr, true))
        << error;
    return report;
  }
};

TEST_F(GlobalPlacementTest, AWalkWithoutAPickIsPlacedAndNeverReliablyWrong) {
  SimulateRecordingResult simulated;
  const std::string recording = SimulateOffice({}, "walk.rec", &simulated);
  ASSERT_FALSE(HasFailure());

  // Placed, tracked to the end, and never RELIABLE while more than 1 m off.
  const EvalReport placed = EvaluateWithoutPick({}, recording);
  ASSERT_FALSE(HasFailure());
  EXPECT_GT(placed.global_searches, 0u);
  EXPECT_GT(placed.first_search_s, 0.0) << "a search waits for walls";
  EXPECT_LE(placed.first_search_s, placed.time_to_first_reliable_s) << "and places the wearer";
  EXPECT_GE(placed.first_search_truth, 0) << "the office's first search holds the truth";
  EXPECT_GT(placed.poses, placed.unaligned_poses) << "placed for most of the walk";
  EXPECT_EQ(placed.false_reliable_poses, 0u);
  EXPECT_LT(placed.max_error_m, 1.0);
  EXPECT_EQ(placed.divergences, 0u);
  EXPECT_GT(placed.time_to_first_reliable_s, 0.0);
  EXPECT_GT(placed.accepted, 0u);
  // The probability's Brier score is the track's, and better than a coin's (0.25).
  double brier = 0;
  for (const EvalPose& p : placed.track)
    brier += std::pow(p.probability - (p.error_m <= 1.0 ? 1.0 : 0.0), 2);
  ASSERT_FALSE(placed.track.empty());
  EXPECT_NEAR(placed.brier, brier / static_cast<double>(placed.track.size()), 1e-12);
  EXPECT_LT(placed.brier, 0.25);
  // The first step is timed as the placement is, from the first pose published: the
  // wearer walks before the search can place them, and it is one of the published poses.
  ASSERT_GE(placed.first_step_s, 0.0) << "the office walk walks";
  EXPECT_LT(placed.first_step_s, placed.time_to_first_reliable_s);
  const int64_t t0 = placed.plan_poses.front().source_stamp_ns();
  EXPECT_TRUE(std::any_of(placed.plan_poses.begin(), placed.plan_poses.end(), [&](const auto& p) {
    return std::abs(static_cast<double>(p.source_stamp_ns() - t0) * 1e-9 - placed.first_step_s) <
           1e-6;
  }));
  // The scored poses (placed) begin after it.
  EXPECT_GE(static_cast<double>(placed.track.front().stamp_ns - t0) * 1e-9, placed.first_step_s);
  std::printf(
      "placed after %zu of %zu poses, %zu searches; first reliable after %.1f s; error "
      "mean %.2f m, max %.2f m\n",
      placed.unaligned_poses, placed.unaligned_poses + placed.poses, placed.global_searches,
      placed.time_to_first_reliable_s, placed.mean_error_m, placed.max_error_m);
}

TEST_F(GlobalPlacementTest, TheSearchesKeepToTheirShareOfACore) {
  SimulateRecordingResult simulated;
  const std::string recording = SimulateOffice({}, "walk.rec", &simulated);
  ASSERT_FALSE(HasFailure());
  v1::FloorposedConfig config;
  ASSERT_GT(EvaluateWithoutPick(config, recording).global_searches, 1u)
      << "the office walk searches more than once";
  // A share that one search of the office overdraws for the rest of the walk.
  config.mutable_limits()->set_search_cpu(1e-7);
  EXPECT_EQ(EvaluateWithoutPick(config, recording).global_searches, 1u);
  // None: without a pick the wearer is never placed.
  config.mutable_limits()->set_search_cpu(0);
  const EvalReport none = EvaluateWithoutPick(config, recording);
  EXPECT_EQ(none.global_searches, 0u);
  EXPECT_EQ(none.poses, 0u);
  EXPECT_GT(none.unaligned_poses, 0u);
}

TEST_F(GlobalPlacementTest, AWrongPickIsFlaggedAndUndone) {
  // simulate --kidnap: the pick is 10 m and 90 degrees off at the wearer.
  sim::SimulatorOptions o;
  o.kidnap_m = 10.0;
  o.kidnap_rad = M_PI / 2;
  SimulateRecordingResult simulated;
  const std::string recording = SimulateOffice(o, "kidnapped.rec", &simulated);
  ASSERT_FALSE(HasFailure());
  std::string error;
  const Se2& e = simulated.simulation.pick_error;
  EXPECT_NEAR(std::abs(e.theta), M_PI / 2, 1e-9);
  const Eigen::Vector2d wearer =
      simulated.simulation.steps[simulated.simulation.pick_step].true_plan.position;
  EXPECT_NEAR((e * wearer - wearer).norm(), 10.0, 1e-6);

  v1::FloorposedConfig config;
  config.set_plan_path(kPlanPath);
  // Flagged UNRELIABLE at once (the pick is doubted until a search of the plan checks
  // it), placed right within a minute, never RELIABLE while wrong.
  EvalReport undone;
  ASSERT_TRUE(Evaluate(config, recording, Baseline::kNone, &undone, &error)) << error;
  EXPECT_GE(undone.time_to_unreliable_s, 0.0);
  EXPECT_LE(undone.time_to_unreliable_s, 5.0);
  EXPECT_GE(undone.time_to_recovered_s, 0.0);
  EXPECT_LE(undone.time_to_recovered_s, 60.0);
  EXPECT_EQ(undone.false_reliable_poses, 0u);
  EXPECT_LT(undone.final_error_m, 1.0);
  std::printf("kidnapped: UNRELIABLE after %.1f s, recovered after %.1f s, final error %.2f m\n",
              undone.time_to_unreliable_s, undone.time_to_recovered_s, undone.final_error_m);
}

// Two floors of the office's layout in a .floors set: the walk climbs a flight of stairs
// halfway (simulate --stairs-at 0.5). The daemon follows it upstairs once, ends on the
// right floor, and tracks as well as on the same walk without the stairs.
TEST_F(GlobalPlacementTest, ATwoFloorWalkEndsOnTheRightFloorAsAccurately) {
  const FloorPlanParse plan = platform::LoadFloorPlan(kPlanPath);
  ASSERT_TRUE(plan.ok()) << plan.error;
  sim::SimulatorOptions o;
  o.seed = 1;
  o.scenario = sim::Scenario::kOffice;
  std::string error;
  SimulateRecordingResult flat, stairs;
  ASSERT_TRUE(SimulateToRecording(plan.plan, o, nullptr, {}, Path("flat.rec"), &flat, &error))
      << error;
  SimulateRecordingOptions climb;
  climb.stairs_at = 0.5;
  ASSERT_TRUE(
      SimulateToRecording(plan.plan, o, nullptr, climb, Path("stairs.rec"), &stairs, &error))
      << error;
  ASSERT_EQ(stairs.simulation.steps.size(), flat.simulation.steps.size() + 33);  // 10 s of poses
  EXPECT_EQ(stairs.simulation.steps.back().floor, 1);

  v1::FloorposedConfig config;
  config.set_plan_path(kPlanPath);
  EvalReport one;
  ASSERT_TRUE(Evaluate(config, Path("flat.rec"), Baseline::kNone, &one, &error)) << error;
  config.set_plan_path(
      Write("office.floors", std::string("0 0.0 ") + kPlanPath + "\n1 3.5 " + kPlanPath + "\n"));
  EvalReport two;
  ASSERT_TRUE(Evaluate(config, Path("stairs.rec"), Baseline::kNone, &two, &error)) << error;
  EXPECT_EQ(two.floor_changes, 1u);
  ASSERT_FALSE(two.plan_poses.empty());
  EXPECT_EQ(two.plan_poses.back().floor(), "1");
  EXPECT_LE(two.wrong_floor_poses, 10u) << "at most the 2 s the change waits, and the climb";
  EXPECT_EQ(two.divergences, 0u);
  EXPECT_LT(two.mean_error_m, one.mean_error_m + 0.1);
  EXPECT_LT(two.max_error_m, std::max(1.5, 1.5 * one.max_error_m));
}

}  // namespace
}  // namespace floorpose::tools
