// The estimator through the daemon's code (Evaluate drives the Engine as
// floorposed does): with a wall pick, without one, and after a wrong one, on the bundled
// office.
#include <gtest/gtest.h>

#include <cmath>

#include "platform/floor_plan_io.h"
#include "tests/test_util.h"
#include "tools/lib/evaluation.h"
#include "tools/lib/simulate_recording.h"

namespace floorpose::tools {
namespace {

class MclEngineTest : public testing::TempDirTest {
 protected:
  static constexpr const char* kPlanPath = FLOORPOSE_SOURCE_DIR "/tools/demo/office.geojson";
  std::string Simulate(sim::SimulatorOptions o, const std::string& name) {
    const FloorPlanParse plan = platform::LoadFloorPlan(kPlanPath);
    EXPECT_TRUE(plan.ok()) << plan.error;
    o.seed = 2;
    o.scenario = sim::Scenario::kOffice;
    std::string error;
    SimulateRecordingResult simulated;
    const std::string recording = Path(name);
    EXPECT_TRUE(SimulateToRecording(plan.plan, o, nullptr, {}, recording, &simulated, &error))
        << error;
    return recording;
  }
  EvalReport Run(const std::string& recording, bool no_pick) {
    v1::FloorposedConfig config;
    config.set_plan_path(kPlanPath);
    EvalReport report;
    std::string error;
    EXPECT_TRUE(Evaluate(config, recording, Baseline::kNone, &report, &error, nullptr, no_pick))
        << error;
    std::printf(
        "%zu poses: error mean %.2f m, max %.2f m; RELIABLE %.1f%%, %zu more than 1 m off\n",
        report.poses, report.mean_error_m, report.max_error_m, 100 * report.reliable_fraction,
        report.false_reliable_poses);
    return report;
  }
};

TEST_F(MclEngineTest, AfterAPickTracksAndIsReliableOnlyWhenRight) {
  const EvalReport r = Run(Simulate({}, "walk.rec"), false);
  ASSERT_GT(r.poses, 500u);
  EXPECT_LT(r.mean_error_m, 0.3);
  EXPECT_EQ(r.divergences, 0u);
  EXPECT_EQ(r.false_reliable_poses, 0u);
  EXPECT_GT(r.reliable_fraction, 0.8);
  // The belief's own probability, published with every pose.
  ASSERT_FALSE(r.plan_poses.empty());
  const v1::Reliability& last = r.plan_poses.back().reliability();
  EXPECT_GE(last.probability(), 0.0);
  EXPECT_LE(last.probability(), 1.0);
}

TEST_F(MclEngineTest, WithoutAPickASearchSeedsTheBelief) {
  const EvalReport r = Run(Simulate({}, "walk.rec"), true);
  EXPECT_GT(r.global_searches, 0u);
  EXPECT_GT(r.poses, 0u) << "placed";
  EXPECT_EQ(r.false_reliable_poses, 0u);
  EXPECT_GT(r.time_to_first_reliable_s, 0.0);
}

TEST_F(MclEngineTest, AWrongPickIsNeverReliableWhileWrong) {
  sim::SimulatorOptions o;
  o.kidnap_m = 10.0;
  o.kidnap_rad = M_PI / 2;
  const EvalReport r = Run(Simulate(o, "kidnapped.rec"), false);
  EXPECT_EQ(r.false_reliable_before_recovered, 0u);
  EXPECT_GE(r.time_to_unreliable_s, 0.0);
  EXPECT_GE(r.time_to_recovered_s, 0.0) << "the search reseeds the belief at the truth";
}

}  // namespace
}  // namespace floorpose::tools
