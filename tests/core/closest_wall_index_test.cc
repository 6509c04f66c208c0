// The closest-wall grid against its oracle, BruteForceClosestWall: for seeded random
// plans and query points inside and around them, the grid finds a wall at the same
// distance whenever the oracle finds one within max_distance_m, and nothing otherwise.
#include "core/closest_wall_index.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "core/random.h"
#include "tests/test_util.h"

namespace floorpose {
namespace {

using testing::RandomVector2;

// Random walls in a 20 x 15 m box: long and short, every orientation, some crossing.
FloorPlan RandomPlan(uint64_t seed, int segments) {
  SplitMix64 rng(seed);
  std::vector<Segment> raw;
  for (int i = 0; i < segments; ++i) {
    const Eigen::Vector2d a = RandomVector2(rng, {0, 0}, {20, 15});
    const double angle = rng.Uniform(-M_PI, M_PI);
    const double length = rng.Uniform() < 0.2 ? rng.Uniform(0.01, 0.3) : rng.Uniform(0.3, 8);
    raw.push_back({a, a + length * Eigen::Vector2d(std::cos(angle), std::sin(angle))});
  }
  auto parse = MakeFloorPlan("random-" + std::to_string(seed), std::move(raw));
  EXPECT_TRUE(parse.ok()) << parse.error;
  return parse.plan;
}

struct Agreement {
  int hits = 0;
  int misses = 0;
};

// Compares the grid with the oracle on `queries` points drawn over the plan's bounds
// grown by `margin`; returns how many had a wall in range.
Agreement ExpectAgreement(const FloorPlan& plan, const ClosestWallIndex::Options& options,
                          uint64_t seed, int queries, double margin) {
  const ClosestWallIndex index(plan, options);
  SplitMix64 rng(seed);
  const Eigen::Vector2d lo = plan.min - Eigen::Vector2d::Constant(margin);
  const Eigen::Vector2d hi = plan.max + Eigen::Vector2d::Constant(margin);
  Agreement a;
  for (int i = 0; i < queries; ++i) {
    Eigen::Vector2d q = RandomVector2(rng, lo, hi);
    // Every tenth query lies on a wall, where distances are zero and ties are common.
    if (i % 10 == 0) {
      const Segment& s = plan.segments[rng.Next() % plan.segments.size()];
      q = s.a + rng.Uniform() * (s.b - s.a);
    }
    const auto want = BruteForceClosestWall(plan, q, options.max_distance_m);
    const auto got = index.Query(q);
    if (!want) {
      EXPECT_FALSE(got.has_value())
          << "query (" << q.transpose() << ") found segment " << got->segment << " at "
          << got->distance << " m, beyond max_distance_m";
      ++a.misses;
      continue;
    }
    ++a.hits;
    if (!got) {
      ADD_FAILURE() << "query (" << q.transpose() << ") found nothing; the oracle found "
                    << "segment " << want->segment << " at " << want->distance << " m";
      continue;
    }
    // Ties may pick different segments; the distance is what must agree.
    EXPECT_NEAR(got->distance, want->distance, 1e-9) << "query (" << q.transpose() << ")";
    // The hit is self-consistent: its point is on its segment, at its distance.
    const Segment& s = plan.segments[got->segment];
    EXPECT_NEAR((ClosestPointOnSegment(s, q) - got->point).norm(), 0.0, 1e-12);
    EXPECT_NEAR((got->point - q).norm(), got->distance, 1e-12);
    EXPECT_NEAR(got->normal.norm(), 1.0, 1e-12);
    EXPECT_NEAR(got->normal.dot(s.b - s.a), 0.0, 1e-9);
  }
  return a;
}

struct GridCase {
  double cell_m;
  double max_distance_m;
};

void PrintTo(const GridCase& c, std::ostream* os) {
  *os << "cell " << c.cell_m << " m, max distance " << c.max_distance_m << " m";
}

ClosestWallIndex::Options OptionsOf(const GridCase& c) {
  ClosestWallIndex::Options options;
  options.cell_m = c.cell_m;
  options.max_distance_m = c.max_distance_m;
  return options;
}

class ClosestWallIndexRandomTest : public ::testing::TestWithParam<GridCase> {};

TEST_P(ClosestWallIndexRandomTest, AgreesWithBruteForce) {
  const GridCase c = GetParam();
  const ClosestWallIndex::Options options = OptionsOf(c);
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const FloorPlan plan = RandomPlan(seed, 10 + 25 * static_cast<int>(seed));
    const Agreement a = ExpectAgreement(plan, options, 100 + seed, 5000, c.max_distance_m + 2.0);
    // The query region is large enough that both outcomes were exercised.
    EXPECT_GT(a.hits, 500);
    EXPECT_GT(a.misses, 50);
  }
}

TEST_P(ClosestWallIndexRandomTest, StepCrossingsAgreeWithEveryWall) {
  const GridCase c = GetParam();
  const ClosestWallIndex::Options options = OptionsOf(c);
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const FloorPlan plan = RandomPlan(seed, 10 + 25 * static_cast<int>(seed));
    const ClosestWallIndex index(plan, options);
    SplitMix64 rng(200 + seed);
    const Eigen::Vector2d lo = plan.min.array() - 2.0, hi = plan.max.array() + 2.0;
    int crossing = 0;
    for (int i = 0; i < 3000; ++i) {
      const Eigen::Vector2d p(rng.Uniform(lo.x(), hi.x()), rng.Uniform(lo.y(), hi.y()));
      // Steps from a few centimetres to a few metres, in every direction.
      const double length = std::exp(rng.Uniform(std::log(0.02), std::log(4.0)));
      const double angle = rng.Uniform(-M_PI, M_PI);
      const Eigen::Vector2d q = p + length * Eigen::Vector2d(std::cos(angle), std::sin(angle));
      const bool want = StepCrossesPlan(p, q, plan);
      EXPECT_EQ(index.StepCrossesWall(p, q), want)
          << "step (" << p.transpose() << ") -> (" << q.transpose() << ")";
      crossing += want;
    }
    EXPECT_GT(crossing, 100) << "both outcomes exercised";
  }
}

INSTANTIATE_TEST_SUITE_P(Grids, ClosestWallIndexRandomTest,
                         ::testing::Values(GridCase{0.25, 3.0},  // the defaults
                                           GridCase{0.1, 0.5}, GridCase{0.5, 1.5},
                                           GridCase{1.0, 0.3}, GridCase{0.05, 0.2}),
                         [](const ::testing::TestParamInfo<GridCase>& c) {
                           auto cm = [](double m) { return std::to_string(std::lround(m * 100)); };
                           return "Cell" + cm(c.param.cell_m) + "cmMax" +
                                  cm(c.param.max_distance_m) + "cm";
                         });

// Distance reads the distance grid near the walls and Query beyond: within the grid's
// interpolation error of the oracle (core/distance_grid.h) near a wall, exact farther out,
// infinite beyond max_distance_m.
TEST(ClosestWallIndexTest, DistanceAgreesWithBruteForce) {
  ClosestWallIndex::Options options;
  const double h = options.grid_cell_m, near = ClosestWallIndex::kGridNearM;
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const FloorPlan plan = RandomPlan(seed, 10 + 25 * static_cast<int>(seed));
    const ClosestWallIndex index(plan, options);
    SplitMix64 rng(300 + seed);
    const Eigen::Vector2d lo = plan.min.array() - 4.0, hi = plan.max.array() + 4.0;
    int on_grid = 0, beyond = 0;
    double worst_on_wall = 0;
    for (int i = 0; i < 20000; ++i) {
      Eigen::Vector2d q = RandomVector2(rng, lo, hi);
      if (i % 4 == 0) {  // a quarter on a wall or within 20 cm of one
        const Segment& s = plan.segments[rng.Next() % plan.segments.size()];
        q = s.a + rng.Uniform() * (s.b - s.a) + RandomVector2(rng, {-0.1, -0.1}, {0.1, 0.1});
      }
      const auto want = BruteForceClosestWall(plan, q, options.max_distance_m);
      const double got = index.Distance(q);
      if (!want) {
        EXPECT_EQ(got, std::numeric_limits<double>::infinity()) << "(" << q.transpose() << ")";
        ++beyond;
        continue;
      }
      const double d = want->distance;
      if (d < near) {
        // Interpolating d^2 errs by at most h^2 / 2 at a segment's end, and by its slope
        // (2 d) times h where two walls' distances meet.
        EXPECT_NEAR(got * got, d * d, h * h / 2 + 2 * d * h) << "(" << q.transpose() << ")";
        if (d < 0.2) worst_on_wall = std::max(worst_on_wall, std::abs(got - d));
        ++on_grid;
      } else if (d > near + 2 * h) {
        EXPECT_NEAR(got, d, 1e-9) << "(" << q.transpose() << ")";
      }
    }
    EXPECT_LT(worst_on_wall, 0.75 * h) << "seed " << seed;
    EXPECT_GT(on_grid, 5000);
    EXPECT_GT(beyond, 500);
  }
}

// Distance(p, far_m) skips the search only where the distance grid shows every wall at
// least far_m away, and otherwise answers as Distance(p).
TEST(ClosestWallIndexTest, DistanceSkipsOnlyWallsCertainlyFar) {
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const FloorPlan plan = RandomPlan(seed, 10 + 25 * static_cast<int>(seed));
    const ClosestWallIndex index(plan);
    SplitMix64 rng(700 + seed);
    const Eigen::Vector2d lo = plan.min.array() - 4.0, hi = plan.max.array() + 4.0;
    for (const double far_m : {0.5, 0.93, 2.0}) {
      int skipped = 0, beyond_far = 0;
      for (int i = 0; i < 20000; ++i) {
        const Eigen::Vector2d q = RandomVector2(rng, lo, hi);
        const double got = index.Distance(q, far_m);
        const auto want = BruteForceClosestWall(plan, q, 1e9);
        ASSERT_TRUE(want.has_value());
        beyond_far += want->distance >= far_m + 0.1;
        if (got == std::numeric_limits<double>::infinity()) {
          EXPECT_GE(want->distance, far_m) << "(" << q.transpose() << ")";
          skipped += want->distance <= index.max_distance_m();
        } else {
          EXPECT_EQ(got, index.Distance(q)) << "(" << q.transpose() << ")";
        }
      }
      // Within reach, nearly every point that far is answered without a search.
      EXPECT_GT(skipped, 0) << "seed " << seed << " far " << far_m;
      EXPECT_GT(beyond_far, skipped / 2) << "seed " << seed << " far " << far_m;
    }
  }
}

TEST(ClosestWallIndexTest, SingleHorizontalSegment) {
  // Flat bounds (min.y == max.y) must still give a usable grid.
  const auto parse = MakeFloorPlan("one", {{{0, 0}, {5, 0}}});
  ASSERT_TRUE(parse.ok());
  const ClosestWallIndex index(parse.plan);
  const auto hit = index.Query({2, 1});
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->distance, 1.0, 1e-12);
  EXPECT_EQ(hit->point, Eigen::Vector2d(2, 0));
  EXPECT_FALSE(index.Query({2, 3.5}).has_value());   // beyond the default 3 m
  EXPECT_FALSE(index.Query({-100, 0}).has_value());  // outside the grid
  ExpectAgreement(parse.plan, {}, 7, 2000, 4.0);
}

TEST(ClosestWallIndexTest, HugeExtentsStayBoundedAndExact) {
  // A plan drawn in millimetres (50 m read as 50 km) or with a stray far-away segment
  // must neither exhaust memory nor overflow the grid size: the cells grow instead,
  // and the answers stay those of the oracle.
  for (const double far : {5e4, 3e6, 1e12}) {
    SCOPED_TRACE("far wall at " + std::to_string(far));
    auto parse = MakeFloorPlan(
        "far", {{{0, 0}, {4, 0}}, {{0, 0}, {0, 3}}, {{far, 0.6 * far}, {far + 2, 0.6 * far + 1}}});
    ASSERT_TRUE(parse.ok()) << parse.error;
    const ClosestWallIndex index(parse.plan);
    EXPECT_LE(index.cells(), size_t{1} << 24);
    SplitMix64 rng(8);
    for (int i = 0; i < 2000; ++i) {
      // Queries around both ends of the plan, where the walls are.
      const Eigen::Vector2d base = i % 2 ? Eigen::Vector2d(far, 0.6 * far) : Eigen::Vector2d(0, 0);
      const Eigen::Vector2d q = base + RandomVector2(rng, {-5, -5}, {7, 6});
      const auto want = BruteForceClosestWall(parse.plan, q, 3.0);
      const auto got = index.Query(q);
      ASSERT_EQ(got.has_value(), want.has_value()) << "query (" << q.transpose() << ")";
      if (want) {
        // Far from the origin doubles carry fewer decimals; allow for that rounding.
        EXPECT_NEAR(got->distance, want->distance, 1e-9 + 1e-15 * q.norm());
      }
    }
  }
}

TEST(ClosestWallIndexTest, NonFiniteQueriesReturnNothing) {
  const FloorPlan plan = RandomPlan(3, 40);
  const ClosestWallIndex index(plan);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(index.Query({nan, 5}).has_value());
  EXPECT_FALSE(index.Query({5, nan}).has_value());
  EXPECT_FALSE(index.Query({nan, nan}).has_value());
  EXPECT_FALSE(index.Query({inf, 5}).has_value());
  EXPECT_FALSE(index.Query({5, -inf}).has_value());
  EXPECT_FALSE(index.Query({1e300, -1e300}).has_value());
  EXPECT_GT(index.cells(), 0u);
  EXPECT_GT(index.MemoryBytes(), 0u);
}

TEST(ClosestWallIndexTest, RealPlansAgreeWithBruteForce) {
  const auto data = testing::DataDir();
  if (!data) GTEST_SKIP() << testing::kNoDataMessage;
  const auto files = testing::RealPlanTextFiles(*data);
  ASSERT_FALSE(files.empty()) << "no floorplans/*/*.txt under " << *data;
  uint64_t seed = 300;
  for (const auto& path : files) {
    SCOPED_TRACE(path.string());
    const auto parse = ParseTextFloorPlan(testing::ReadText(path), path.stem().string());
    ASSERT_TRUE(parse.ok()) << parse.error;
    const Agreement a = ExpectAgreement(parse.plan, {}, ++seed, 3000, 5.0);
    EXPECT_GT(a.hits, 0);
  }
}

}  // namespace
}  // namespace floorpose
