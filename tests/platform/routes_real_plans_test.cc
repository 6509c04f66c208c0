// Issue 12's route checks on every real floor plan of the developer data set
// ($FLOORPOSE_DATA/floorplans/*/*.txt, skipped when unset): between passable points drawn
// at random (seeded per plan), a route never crosses a wall or comes closer than
// the body radius, and is within 5% of a brute-force shortest path on the same grid;
// where brute force finds no path, the planner refuses. Timings are printed, not
// asserted (floorpose bench route measures them).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/route_planner.h"
#include "platform/floor_plan_io.h"
#include "tests/route_test_util.h"
#include "tests/test_util.h"

namespace floorpose {
namespace {

TEST(RoutesRealPlansTest, ClearOfWallsAndNearlyShortest) {
  const auto data = testing::DataDir();
  if (!data) GTEST_SKIP() << testing::kNoDataMessage;
  const auto files = testing::RealPlanTextFiles(*data);
  ASSERT_FALSE(files.empty()) << "no plans under " << (*data / "floorplans");
  for (const auto& file : files) {
    SCOPED_TRACE(file.string());
    const FloorPlanParse parse = platform::LoadFloorPlan(file.string());
    ASSERT_TRUE(parse.ok()) << parse.error;
    const FloorPlan& plan = parse.plan;
    const RoutePlanner planner(plan);
    std::vector<int> passable;
    for (int cell = 0; cell < static_cast<int>(planner.grid().size()); ++cell)
      if (planner.Passable(cell)) passable.push_back(cell);
    ASSERT_FALSE(passable.empty());
    SplitMix64 rng(FloorPlanDigest(plan));
    auto draw = [&] {
      const size_t i = static_cast<size_t>(rng.Uniform(0, static_cast<double>(passable.size())));
      return planner.grid().CellCentre(passable[std::min(i, passable.size() - 1)]);
    };
    int routed = 0, refused = 0;
    double slowest_ms = 0;
    for (int pair = 0; pair < 12 && routed < 3; ++pair) {
      const Eigen::Vector2d from = draw(), to = draw();
      SCOPED_TRACE(::testing::Message() << "from " << from.transpose() << " to " << to.transpose());
      const auto t0 = std::chrono::steady_clock::now();
      const Route route = planner.Plan(from, to);
      slowest_ms = std::max(
          slowest_ms,
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      const testing::Reference ref = testing::BruteForceShortest(planner, from, to);
      if (!std::isfinite(ref.centres_m)) {
        EXPECT_FALSE(route.ok());
        EXPECT_NE(route.error.find("no path"), std::string::npos) << route.error;
        ++refused;
        continue;
      }
      ASSERT_TRUE(route.ok()) << route.error;
      EXPECT_EQ(route.path.front(), from);
      EXPECT_EQ(route.path.back(), to);
      EXPECT_GE(testing::PathClearance(route.path, plan.segments),
                planner.options().body_radius_m - 1e-9);
      EXPECT_LE(route.length_m, 1.05 * ref.centres_m + ref.ends_m);
      EXPECT_GE(route.length_m, ref.centres_m / 1.013 - ref.ends_m - 1e-9);
      ++routed;
    }
    EXPECT_GE(routed, 2) << "too few reachable room pairs to check";
    std::printf("%s: %d routes checked, %d refused, slowest %.1f ms\n", file.filename().c_str(),
                routed, refused, slowest_ms);
  }
}

}  // namespace
}  // namespace floorpose
