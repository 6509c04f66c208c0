#include "core/raster_plan.h"

#include "core/closest_wall_index.h"
#include "tests/test_util.h"

namespace floorpose {
namespace {

// A 40 x 30 cell raster (0.1 m) with an L of walls: a row at y = 0.55 m and a column at
// x = 3.05 m, plus one speck far from both.
OccupancyRaster LRaster() {
  OccupancyRaster r;
  r.width = 40;
  r.height = 30;
  r.resolution_m = 0.1;
  r.origin = {0.0, 0.0};
  r.occupied.assign(r.width * r.height, 0);
  auto set = [&](int col, int row_from_bottom) {
    r.occupied[(r.height - 1 - row_from_bottom) * r.width + col] = 1;
  };
  for (int c = 2; c <= 30; ++c) set(c, 5);   // horizontal wall, cell centres y = 0.55
  for (int k = 6; k <= 25; ++k) set(30, k);  // vertical wall, cell centres x = 3.05
  set(10, 20);                               // a speck
  return r;
}

TEST(RasterPlanTest, CellsBecomeSegmentsAlongTheWall) {
  RasterPlanReport report;
  const FloorPlanParse parsed = FloorPlanFromRaster(LRaster(), "l", {}, &report);
  ASSERT_TRUE(parsed.ok()) << parsed.error;
  EXPECT_EQ(report.occupied, 29u + 20u + 1u);
  EXPECT_EQ(report.isolated, 1u);
  EXPECT_EQ(parsed.plan.segments.size(), 49u);
  EXPECT_EQ(parsed.dropped_segments, 1u);

  // Points on either wall, away from the corner, find it at the right distance with the
  // wall's normal; the speck is gone.
  const ClosestWallIndex index(parsed.plan);
  const auto below = index.Query({1.5, 0.25});
  ASSERT_TRUE(below.has_value());
  EXPECT_NEAR(below->distance, 0.30, 1e-6);
  EXPECT_NEAR(std::abs(below->normal.y()), 1.0, 1e-6);
  const auto left = index.Query({2.55, 2.0});
  ASSERT_TRUE(left.has_value());
  EXPECT_NEAR(left->distance, 0.50, 1e-6);
  EXPECT_NEAR(std::abs(left->normal.x()), 1.0, 1e-6);
  const auto near_speck = index.Query({1.05, 2.05});
  ASSERT_TRUE(near_speck.has_value());
  EXPECT_GT(near_speck->distance, 1.4);
}

TEST(RasterPlanTest, DiagonalWallKeepsItsDirection) {
  OccupancyRaster r;
  r.width = r.height = 20;
  r.resolution_m = 0.05;
  r.occupied.assign(400, 0);
  for (int i = 0; i < 20; ++i) r.occupied[(19 - i) * 20 + i] = 1;  // y = x
  const FloorPlanParse parsed = FloorPlanFromRaster(r, "diag");
  ASSERT_TRUE(parsed.ok()) << parsed.error;
  for (const Segment& s : parsed.plan.segments) {
    const Eigen::Vector2d d = (s.b - s.a).normalized();
    EXPECT_NEAR(std::abs(d.x()), std::sqrt(0.5), 1e-6);
    EXPECT_NEAR(std::abs(d.y()), std::sqrt(0.5), 1e-6);
  }
  // The staircase is one continuous line: a point beside it is 0.1 m from it everywhere.
  const ClosestWallIndex index(parsed.plan);
  for (double t = 0.2; t < 0.8; t += 0.05) {
    const Eigen::Vector2d p = Eigen::Vector2d(t, t) + 0.1 * Eigen::Vector2d(-1, 1).normalized();
    const auto hit = index.Query(p);
    ASSERT_TRUE(hit.has_value());
    EXPECT_NEAR(hit->distance, 0.1, 0.01) << "at " << t;
  }
}

TEST(RasterPlanTest, MalformedRastersFailClearly) {
  OccupancyRaster r = LRaster();
  r.occupied.pop_back();
  EXPECT_THAT(FloorPlanFromRaster(r, "x").error, ::testing::HasSubstr("cells for 40 x 30"));
  r = LRaster();
  r.resolution_m = -1;
  EXPECT_THAT(FloorPlanFromRaster(r, "x").error, ::testing::HasSubstr("resolution"));
  r = LRaster();
  r.width = 0;
  EXPECT_THAT(FloorPlanFromRaster(r, "x").error, ::testing::HasSubstr("bad size"));
  r = LRaster();
  std::fill(r.occupied.begin(), r.occupied.end(), 0);
  EXPECT_THAT(FloorPlanFromRaster(r, "x").error, ::testing::HasSubstr("no occupied cells"));
}

}  // namespace
}  // namespace floorpose
