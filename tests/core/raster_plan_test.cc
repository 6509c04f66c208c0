#include "core/raster_plan.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/closest_wall_index.h"
#include "tests/test_util.h"

namespace floorpose {
namespace {

// A raster of free cells, its origin at (0, 0).
OccupancyRaster FreeRaster(int width, int height, double resolution_m) {
  OccupancyRaster r;
  r.width = width;
  r.height = height;
  r.resolution_m = resolution_m;
  r.occupied.assign(static_cast<size_t>(width) * height, 0);
  return r;
}

// A 40 x 30 cell raster (0.1 m) with an L of walls: a row at y = 0.55 m and a column at
// x = 3.05 m, plus one speck far from both.
OccupancyRaster LRaster() {
  OccupancyRaster r = FreeRaster(40, 30, 0.1);
  auto set = [&](int col, int row_from_bottom) {
    r.occupied[(r.height - 1 - row_from_bottom) * r.width + col] = 1;
  };
  for (int c = 2; c <= 30; ++c) set(c, 5);   // horizontal wall, cell centres y = 0.55
  for (int k = 6; k <= 25; ++k) set(30, k);  // vertical wall, cell centres x = 3.05
  set(10, 20);                               // a speck
  return r;
}

// Whether the plan has a segment from a to b (either way round), to 1e-6 m.
bool HasSegment(const FloorPlan& plan, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  for (const Segment& s : plan.segments)
    if (((s.a - a).norm() < 1e-6 && (s.b - b).norm() < 1e-6) ||
        ((s.a - b).norm() < 1e-6 && (s.b - a).norm() < 1e-6))
      return true;
  return false;
}

// The largest distance from an occupied cell's centre to the plan's walls.
double FarthestCell(const OccupancyRaster& r, const FloorPlan& plan) {
  const ClosestWallIndex index(plan);
  double worst = 0;
  for (int row = 0; row < r.height; ++row) {
    for (int col = 0; col < r.width; ++col) {
      if (!r.occupied[row * r.width + col]) continue;
      const Eigen::Vector2d centre =
          r.origin + r.resolution_m * Eigen::Vector2d(col + 0.5, r.height - 1 - row + 0.5);
      const auto hit = index.Query(centre);
      worst = std::max(worst, hit ? hit->distance : std::numeric_limits<double>::infinity());
    }
  }
  return worst;
}

TEST(RasterPlanTest, AWallsCellsBecomeOneLineAlongIt) {
  RasterPlanReport report;
  const FloorPlanParse parsed = FloorPlanFromRaster(LRaster(), "l", {}, &report);
  ASSERT_TRUE(parsed.ok()) << parsed.error;
  EXPECT_EQ(report.occupied, 29u + 20u + 1u);
  EXPECT_EQ(report.isolated, 1u);
  EXPECT_EQ(parsed.dropped_segments, 1u);
  // Each wall is one segment from its first cell's outer edge; the corner's cells, which
  // run along neither, are a piece of their own.
  EXPECT_TRUE(HasSegment(parsed.plan, {0.2, 0.55}, {3.0, 0.55}));
  EXPECT_LE(parsed.plan.segments.size(), 3u);

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
  OccupancyRaster r = FreeRaster(20, 20, 0.05);
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

TEST(RasterPlanTest, AWallTwoCellsThickIsOneLineBetweenThem) {
  OccupancyRaster r = FreeRaster(60, 20, 0.05);
  for (int c = 5; c < 55; ++c) r.occupied[9 * r.width + c] = r.occupied[10 * r.width + c] = 1;
  const FloorPlanParse parsed = FloorPlanFromRaster(r, "thick");
  ASSERT_TRUE(parsed.ok()) << parsed.error;
  ASSERT_EQ(parsed.plan.segments.size(), 1u);
  // Rows 9 and 10 from the top have their centres at y = 0.525 and 0.475.
  EXPECT_TRUE(HasSegment(parsed.plan, {0.25, 0.5}, {2.75, 0.5}));
}

TEST(RasterPlanTest, ATiltedWallIsAFewLinesWithinACellOfItsCells) {
  // A wall rising 0.07 m a metre: a staircase of runs of 14-15 cells, 200 cells in all.
  OccupancyRaster r = FreeRaster(240, 40, 0.05);
  for (int c = 20; c < 220; ++c)
    r.occupied[(30 - static_cast<int>(std::floor(0.07 * (c - 20)))) * r.width + c] = 1;
  const FloorPlanParse parsed = FloorPlanFromRaster(r, "tilted");
  ASSERT_TRUE(parsed.ok()) << parsed.error;
  EXPECT_LE(parsed.plan.segments.size(), 200u / 20);
  EXPECT_LE(FarthestCell(r, parsed.plan), r.resolution_m);
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
