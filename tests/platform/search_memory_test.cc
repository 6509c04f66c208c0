#include "platform/search_memory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace floorpose::platform {
namespace {

constexpr int64_t kSecond = 1'000'000'000;

TEST(SearchMemoryTest, KeepsAPositionPerQuarterMetreForTheWindow) {
  SearchMemory memory;
  // 0.1 m a second along x for 100 s, kept for 60 s.
  for (int i = 0; i <= 100; ++i) memory.AddPosition(i * kSecond, {0.1 * i, 0}, 60.0);
  const std::vector<Eigen::Vector2d> path = memory.PathSince(INT64_MIN);
  ASSERT_FALSE(path.empty());
  // Every third is kept (0.3 m apart), from the first at 40 s or later.
  for (size_t i = 1; i < path.size(); ++i) EXPECT_NEAR((path[i] - path[i - 1]).norm(), 0.3, 1e-9);
  EXPECT_NEAR(path.front().x(), 4.2, 1e-9) << "older than 60 s before the last: dropped";
  EXPECT_NEAR(path.back().x(), 9.9, 1e-9);
  // ...and by stamp: from 90 s on, and between 50 and 70 s.
  for (const Eigen::Vector2d& p : memory.PathSince(90 * kSecond)) EXPECT_GE(p.x(), 9.0 - 1e-9);
  for (const Eigen::Vector2d& p : memory.PathBetween(50 * kSecond, 70 * kSecond)) {
    EXPECT_GE(p.x(), 5.0 - 1e-9);
    EXPECT_LT(p.x(), 7.0);
  }
  EXPECT_TRUE(memory.PathSince(101 * kSecond).empty());
}

TEST(SearchMemoryTest, APositionThatIsNotFiniteIsNotKept) {
  SearchMemory memory;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  memory.AddPosition(0, {nan, 0}, 60.0);
  memory.AddPosition(kSecond, {0, std::numeric_limits<double>::infinity()}, 60.0);
  EXPECT_TRUE(memory.PathSince(INT64_MIN).empty());
  memory.AddPosition(2 * kSecond, {1, 1}, 60.0);
  memory.AddPosition(3 * kSecond, {nan, nan}, 60.0);
  const std::vector<Eigen::Vector2d> path = memory.PathSince(INT64_MIN);
  ASSERT_EQ(path.size(), 1u);
  EXPECT_TRUE(path.front().isApprox(Eigen::Vector2d(1, 1)));
}

TEST(SearchMemoryTest, TheSameWallsForTheSameAlignmentAreNoNewSearch) {
  SearchMemory memory;
  const std::vector<Eigen::Vector2d> walls{{0, 0}, {1, 0}, {2, 0}};
  EXPECT_TRUE(memory.NewSearch(walls, 0));
  EXPECT_FALSE(memory.NewSearch(walls, 0)) << "nothing scanned or dropped since";
  EXPECT_TRUE(memory.NewSearch(walls, 1)) << "another alignment to check";
  EXPECT_FALSE(memory.NewSearch(walls, 1));
  EXPECT_TRUE(memory.NewSearch({{0, 0}, {1, 0}, {2, 0}, {3, 0}}, 1)) << "a wall point more";
  EXPECT_TRUE(memory.NewSearch(walls, 1)) << "one dropped again: not the last search";
}

}  // namespace
}  // namespace floorpose::platform
