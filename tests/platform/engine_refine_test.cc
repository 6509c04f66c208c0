// The two-stage registration of Engine::Run: the whole window finds the basin, the recent
// walls decide where the wearer is now. Older walls carry older SLAM drift.
#include <gtest/gtest.h>

#include "platform/engine.h"
#include "tests/test_util.h"

namespace floorpose::platform {
namespace {

using testing::Deg;
using testing::IsNearlySe2;

TEST(EngineRefineTest, RecentWallsDecideWhereTheWearerIsNow) {
  const FloorPlan plan = testing::AsymmetricRoom();
  const Se2 truth{Deg(10), {1.0, -0.5}};                // T_plan_slam now
  const Se2 drifted = Se2{Deg(3), {0.3, 0.2}} * truth;  // the frame the old walls were seen in
  Engine::Job job;
  for (const Eigen::Vector2d& p : testing::SampleWalls(plan, 0.05)) {
    if (p.x() < 7.0) {
      job.cloud.push_back(drifted.Inverse() * p);  // seen a while ago
    } else {
      job.recent.push_back(truth.Inverse() * p);  // seen in the last seconds
      job.cloud.push_back(job.recent.back());
    }
  }
  job.index = std::make_shared<const ClosestWallIndex>(plan);
  job.initial = Se2{Deg(1), {0.1, 0.1}} * truth;
  const auto clock = [] { return int64_t{0}; };

  Engine::Job whole_only = job;
  whole_only.recent.clear();
  const Engine::Done whole = Engine::Run(std::move(whole_only), clock);
  ASSERT_TRUE(whole.result.converged) << whole.result.reason;
  EXPECT_FALSE(whole.refined);
  // The older walls are the majority, and robust ICP sides with them.
  EXPECT_GT(std::abs(whole.result.T_plan_slam.theta - truth.theta), Deg(0.5));

  const Engine::Done refined = Engine::Run(std::move(job), clock);
  ASSERT_TRUE(refined.refined) << refined.result.reason;
  EXPECT_EQ(refined.result.points, refined.job.recent.size());
  EXPECT_THAT(refined.result.T_plan_slam, IsNearlySe2(truth, 0.01, Deg(0.1)));
  EXPECT_GT(refined.result.iterations, whole.result.iterations);
}

}  // namespace
}  // namespace floorpose::platform
