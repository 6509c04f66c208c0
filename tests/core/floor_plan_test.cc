// Floor plans: the thesis' text format (section 6.4.2) and the cleaning every loader
// goes through. Broken files must give a clear error, never a crash or a huge allocation.
#include "core/floor_plan.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

#include "core/random.h"
#include "tests/test_util.h"

namespace floorpose {
namespace {

using ::testing::HasSubstr;

TEST(FloorPlanTextTest, ParsesGoodInput) {
  // A leading '+', exponents, CRLF line ends and blank lines are all fine.
  const auto parse =
      ParseTextFloorPlan("3\r\n0 0 4 0\r\n\r\n+4 0 4 3.5\n  4 3.5 -1e0 3.5 \n", "room");
  ASSERT_TRUE(parse.ok()) << parse.error;
  EXPECT_EQ(parse.plan.id, "room");
  ASSERT_EQ(parse.plan.segments.size(), 3u);
  EXPECT_EQ(parse.dropped_segments, 0u);
  EXPECT_EQ(parse.plan.segments[1].a, Eigen::Vector2d(4, 0));
  EXPECT_EQ(parse.plan.segments[2].b, Eigen::Vector2d(-1, 3.5));
  EXPECT_EQ(parse.plan.min, Eigen::Vector2d(-1, 0));
  EXPECT_EQ(parse.plan.max, Eigen::Vector2d(4, 3.5));
}

struct BrokenCase {
  const char* name;
  const char* text;
  const char* error_part;  // the error must say this
};

// Test failures name the case rather than dumping its bytes.
void PrintTo(const BrokenCase& c, std::ostream* os) { *os << c.name; }

class FloorPlanTextBrokenTest : public ::testing::TestWithParam<BrokenCase> {};

TEST_P(FloorPlanTextBrokenTest, GivesClearError) {
  const BrokenCase& c = GetParam();
  const auto parse = ParseTextFloorPlan(c.text, "broken");
  EXPECT_FALSE(parse.ok());
  EXPECT_THAT(parse.error, HasSubstr("text floor plan"));
  EXPECT_THAT(parse.error, HasSubstr(c.error_part));
  EXPECT_TRUE(parse.plan.segments.empty());
}

INSTANTIATE_TEST_SUITE_P(
    Cases, FloorPlanTextBrokenTest,
    ::testing::Values(
        BrokenCase{"Empty", "", "segment count missing"},
        BrokenCase{"OnlyWhitespace", " \n\t\n", "segment count missing"},
        BrokenCase{"CountNotANumber", "walls\n0 0 1 0\n", "segment count missing"},
        BrokenCase{"CountLargerThanLines", "3\n0 0 1 0\n1 0 1 1\n",
                   "segment 3 of 3: unexpected end of file"},
        BrokenCase{"LineCut", "2\n0 0 1 0\n1 0 1\n", "segment 2 of 2: unexpected end"},
        BrokenCase{"NotANumber", "2\n0 0 1 0\n1 0 x 1\n", "line 3: not a finite number: 'x'"},
        BrokenCase{"NumberWithGarbage", "1\n0 0 1 0x\n", "not a finite number: '0x'"},
        BrokenCase{"NaN", "1\n0 0 nan 1\n", "line 2: not a finite number: 'nan'"},
        BrokenCase{"Infinity", "1\n0 0 inf 1\n", "not a finite number"},
        BrokenCase{"OutOfRange", "1\n0 0 1e999 1\n", "not a finite number"},
        BrokenCase{"TrailingGarbage", "1\n0 0 1 0\nend\n", "more data after the 1 segments"},
        BrokenCase{"TrailingNumber", "1\n0 0 1 0 5\n", "more data after"},
        BrokenCase{"NegativeCount", "-2\n0 0 1 0\n1 0 1 1\n", "bad segment count"},
        BrokenCase{"ZeroCount", "0\n", "bad segment count"},
        BrokenCase{"FractionalCount", "1.5\n0 0 1 0\n", "bad segment count"},
        BrokenCase{"AbsurdCount", "1e12\n0 0 1 0\n", "bad segment count"},
        // Allowed as a count, but there is no data: must fail fast without reserving
        // memory for ten million segments.
        BrokenCase{"HugeCountNoData", "10000000\n", "segment 1 of 10000000: unexpected end"},
        BrokenCase{"Binary", "\x01\x02\xff\xfe", "segment count missing"}),
    [](const ::testing::TestParamInfo<BrokenCase>& c) { return c.param.name; });

TEST(FloorPlanTextTest, LongBadTokenIsShortenedInTheMessage) {
  const std::string token(1000, 'z');
  const auto parse = ParseTextFloorPlan("1\n0 0 1 " + token + "\n", "p");
  ASSERT_FALSE(parse.ok());
  EXPECT_LT(parse.error.size(), 200u);
}

TEST(FloorPlanTextTest, AllSegmentsDegenerateIsAnError) {
  const auto parse = ParseTextFloorPlan("2\n1 1 1 1\n2 2 2 2\n", "p");
  EXPECT_FALSE(parse.ok());
  EXPECT_THAT(parse.error, HasSubstr("no usable wall segments"));
  EXPECT_EQ(parse.dropped_segments, 2u);
}

TEST(FloorPlanTextTest, MutatedFilesNeverCrash) {
  // Seeded random corruptions of a good file: each parse either succeeds with finite
  // segments or says why it failed.
  const std::string good = "4\n0 0 4 0\n4 0 4 3\n4 3 0 3\n0 3 0 0\n";
  const std::string alphabet = "0123456789 \n.-+eEnaix\t\r";
  SplitMix64 rng(21);
  int ok = 0, failed = 0;
  for (int i = 0; i < 3000; ++i) {
    std::string text = good;
    const int edits = 1 + static_cast<int>(rng.Next() % 4);
    for (int e = 0; e < edits && !text.empty(); ++e) {
      const size_t at = rng.Next() % text.size();
      switch (rng.Next() % 3) {
        case 0: text[at] = alphabet[rng.Next() % alphabet.size()]; break;
        case 1: text.erase(at, 1); break;
        case 2: text.resize(at); break;
      }
    }
    const auto parse = ParseTextFloorPlan(text, "fuzz");
    if (parse.ok()) {
      ++ok;
      for (const Segment& s : parse.plan.segments)
        ASSERT_TRUE(s.a.allFinite() && s.b.allFinite()) << text;
    } else {
      ++failed;
      ASSERT_FALSE(parse.error.empty());
    }
  }
  // Both outcomes happen, so the corruptions exercised the error paths and the good one.
  EXPECT_GT(ok, 0);
  EXPECT_GT(failed, 0);
}

TEST(MakeFloorPlanTest, DropsZeroLengthDuplicateAndNonFiniteSegments) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Segment> raw = {
      {{0, 0}, {4, 0}},            // kept
      {{4, 0}, {4, 3}},            // kept, shares an end with the first
      {{2, 2}, {2, 2}},            // zero length
      {{1, 1}, {1.0005, 1}},       // shorter than 1 mm
      {{0, 0}, {4, 0}},            // duplicate
      {{4, 3}, {4, 0}},            // reversed duplicate
      {{0.0002, 0}, {4, 0.0001}},  // duplicate within the 1 mm rounding
      {{nan, 0}, {1, 1}},          // non-finite
      {{0, 0}, {2, 0}},            // overlaps the first but is a different segment: kept
  };
  const auto parse = MakeFloorPlan("p", raw);
  ASSERT_TRUE(parse.ok()) << parse.error;
  EXPECT_EQ(parse.plan.segments.size(), 3u);
  EXPECT_EQ(parse.dropped_segments, 6u);
  EXPECT_EQ(parse.plan.min, Eigen::Vector2d(0, 0));
  EXPECT_EQ(parse.plan.max, Eigen::Vector2d(4, 3));
}

TEST(MakeFloorPlanTest, BoundsMustBeFinite) {
  // Each coordinate is finite, but the plan's extent overflows a double.
  const auto parse = MakeFloorPlan("p", {{{-1e308, 0}, {-1e308, 1}}, {{1e308, 5}, {1e308, 7}}});
  EXPECT_FALSE(parse.ok());
  EXPECT_THAT(parse.error, HasSubstr("extent"));
}

TEST(MakeFloorPlanTest, EmptyInputIsAnError) {
  const auto parse = MakeFloorPlan("p", {});
  EXPECT_FALSE(parse.ok());
  EXPECT_THAT(parse.error, HasSubstr("no usable wall segments"));
}

TEST(SegmentTest, ClosestPointMatchesDenseSampling) {
  // Oracle: the nearest of 2001 points along the segment is at most half a step farther.
  SplitMix64 rng(22);
  for (int i = 0; i < 300; ++i) {
    const Segment s{testing::RandomVector2(rng, {-5, -5}, {5, 5}),
                    testing::RandomVector2(rng, {-5, -5}, {5, 5})};
    const Eigen::Vector2d p = testing::RandomVector2(rng, {-8, -8}, {8, 8});
    const Eigen::Vector2d c = ClosestPointOnSegment(s, p);
    // c lies on the segment.
    EXPECT_NEAR((c - s.a).norm() + (s.b - c).norm(), s.Length(), 1e-9);
    double best = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= 2000; ++k)
      best = std::min(best, (s.a + (s.b - s.a) * (k / 2000.0) - p).norm());
    const double d = (c - p).norm();
    EXPECT_LE(d, best + 1e-12);
    EXPECT_GE(d, best - 0.5 * s.Length() / 2000.0 - 1e-12);
    // The normal is unit and perpendicular.
    EXPECT_NEAR(s.Normal().norm(), 1.0, 1e-12);
    EXPECT_NEAR(s.Normal().dot(s.b - s.a), 0.0, 1e-9);
  }
  const Segment point{{1, 2}, {1, 2}};
  EXPECT_EQ(ClosestPointOnSegment(point, {5, 5}), Eigen::Vector2d(1, 2));
}

TEST(HiddenPointsTest, CountsPointsBehindAWallFromEveryPositionInReach) {
  const FloorPlan plan = testing::AsymmetricRoom();
  // The wearer walked west of the inner wall (x = 4, y 0..4.5).
  const std::vector<Eigen::Vector2d> west = {{2, 2}, {2, 3}};
  // The west wall in sight; a point behind the inner wall; one on the inner wall, 5 cm
  // past its line (noise: the sight line stops short of it); one out of reach, which
  // tells nothing.
  const std::vector<Eigen::Vector2d> points = {{0, 2}, {6, 2}, {4.05, 2}, {9, 1}};
  EXPECT_EQ(HiddenPoints(points, west, plan, 4.5, 0.3), 1u);
  // Seen once from the other side: not hidden.
  EXPECT_EQ(HiddenPoints(points, {{2, 2}, {2, 3}, {5, 2}}, plan, 4.5, 0.3), 0u);
  // Without the standoff the wall the point lies on hides it too.
  EXPECT_EQ(HiddenPoints(points, west, plan, 4.5, 0.0), 2u);
  // Without a path nothing can be hidden.
  EXPECT_EQ(HiddenPoints(points, {}, plan, 4.5, 0.3), 0u);
  EXPECT_EQ(HiddenPoints({}, west, plan, 4.5, 0.3), 0u);
}

TEST(UnseenWallsTest, CountsWallsInSightOfThePathThatNoPointLiesOn) {
  // A corridor 2 m wide (walls at y = 0 and y = 2, x 0..10); a room behind the north
  // wall (its far wall at y = 3). The wearer walked its middle, x 2..8, and saw only the
  // south wall.
  auto parse = MakeFloorPlan("corridor", {{{0, 0}, {10, 0}}, {{0, 2}, {10, 2}}, {{0, 3}, {10, 3}}});
  ASSERT_TRUE(parse.ok()) << parse.error;
  std::vector<Eigen::Vector2d> path, south;
  for (double x = 2; x <= 8; x += 0.25) path.emplace_back(x, 1);
  for (double x = 0; x <= 10; x += 0.1) south.emplace_back(x, 0.02);
  UnseenWallsOptions options;
  options.walls.reach_m = 2.0;
  const UnseenWalls u = CountUnseenWalls(south, path, parse.plan, options);
  // Within 2 m of the path: x from 0.27 to 9.73 on both corridor walls, samples every
  // 0.25 m, 0.5 to 9.5 (37 a wall); the room's far wall is behind the north wall.
  EXPECT_EQ(u.expected, 74u);
  EXPECT_EQ(u.missed, 37u);  // the north wall, every sample
  // Both walls seen: nothing missed.
  std::vector<Eigen::Vector2d> both = south;
  for (double x = 0; x <= 10; x += 0.1) both.emplace_back(x, 1.97);
  EXPECT_EQ(CountUnseenWalls(both, path, parse.plan, options).missed, 0u);
  // Walls shorter than min_length_m are not expected; a shorter reach expects fewer; no
  // path or no reach, nothing.
  options.walls.min_length_m = 20;
  EXPECT_EQ(CountUnseenWalls(south, path, parse.plan, options).expected, 0u);
  options.walls.min_length_m = 1.5;
  options.walls.reach_m = 1.2;
  EXPECT_LT(CountUnseenWalls(south, path, parse.plan, options).expected, 74u);
  EXPECT_EQ(CountUnseenWalls(south, {}, parse.plan, options).expected, 0u);
  options.walls.reach_m = 0;
  EXPECT_EQ(CountUnseenWalls(south, path, parse.plan, options).expected, 0u);
  // Non-finite points are ignored, not matched.
  options.walls.reach_m = 2.0;
  std::vector<Eigen::Vector2d> bad = south;
  bad.emplace_back(std::numeric_limits<double>::quiet_NaN(), 2.0);
  EXPECT_EQ(CountUnseenWalls(bad, path, parse.plan, options).missed, 37u);
}

TEST(PathCrossingsTest, CountsStepsThroughWallsAndSparesTheirEnds) {
  const FloorPlan plan = testing::AsymmetricRoom();
  // Through the inner wall (x = 4, y 0..4.5) at y = 2, and back.
  EXPECT_EQ(PathCrossings({{3, 2}, {5, 2}, {3, 2}}, plan), 2u);
  EXPECT_EQ(PathCrossings({{3, 2}, {5, 2}}, plan, 0.4), 1u);
  // Along it, or touching it, is no crossing.
  EXPECT_EQ(PathCrossings({{3, 1}, {3, 3}, {4, 3}}, plan), 0u);
  // Through it 0.2 m from its end at (4, 4.5): a crossing, unless spared by a margin.
  EXPECT_EQ(PathCrossings({{3.5, 4.3}, {4.5, 4.3}}, plan), 1u);
  EXPECT_EQ(PathCrossings({{3.5, 4.3}, {4.5, 4.3}}, plan, 0.4), 0u);
  EXPECT_EQ(PathCrossings({{3.5, 4.3}, {4.5, 4.3}}, plan, 0.1), 1u);
  // One step alone, as the tracker checks every pose.
  EXPECT_TRUE(StepCrossesPlan({3, 2}, {5, 2}, plan, 0.4));
  EXPECT_FALSE(StepCrossesPlan({3.5, 4.3}, {4.5, 4.3}, plan, 0.4));
  EXPECT_TRUE(StepCrossesPlan({3.5, 4.3}, {4.5, 4.3}, plan));
  // A path of one point, or none, crosses nothing.
  EXPECT_EQ(PathCrossings({{3, 2}}, plan), 0u);
  EXPECT_EQ(PathCrossings({}, plan), 0u);
}

}  // namespace
}  // namespace floorpose
