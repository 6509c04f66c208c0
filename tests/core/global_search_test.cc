// Global localization without a pick: the branch-and-bound search finds where a cloud of
// wall points in an unknown frame lies on the whole plan, at any heading, returns every
// place that fits as well when rooms look alike, and no translation on its grid beats it.
#include "core/global_search.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "tests/registration_scenarios.h"
#include "tests/sim_test_plans.h"
#include "tests/test_util.h"

namespace floorpose {
namespace {

using testing::Box;
using testing::ErrorAt;
using testing::MakeScan;

// 3 cm of noise and a fifth of the points clutter.
testing::ScanOptions NoisyCluttered() {
  testing::ScanOptions o;
  o.noise_m = 0.03;
  o.clutter_share = 0.2;
  return o;
}

TEST(GlobalSearchTest, FindsTheRoomAtAnyHeadingAndAnyOffset) {
  const FloorPlan plan = testing::AsymmetricRoom();
  const GlobalSearch search(plan);
  SplitMix64 rng(3);
  const testing::ScanOptions o = NoisyCluttered();
  for (int trial = 0; trial < 8; ++trial) {
    const Se2 T_slam_plan = testing::RandomSe2(rng, M_PI, 50.0);  // anywhere, any heading
    const Box window = Box::Around({5, 3.5}, 12);
    const testing::Scan scan = MakeScan(plan, window, T_slam_plan, o, rng);
    GlobalSearchStats stats;
    const std::vector<GlobalPlace> places = search.Search(scan.points, {}, &stats);
    ASSERT_FALSE(places.empty()) << "trial " << trial;
    const auto e = ErrorAt(places[0].T_plan_slam, T_slam_plan.Inverse(), window.Centre());
    EXPECT_LT(e.translation_m, 0.15) << "trial " << trial << ": " << testing::Describe(e);
    EXPECT_LT(e.rotation_rad, testing::Deg(1.0))
        << "trial " << trial << ": " << testing::Describe(e);
    EXPECT_GT(places[0].score, 0.5);
    // Anything else it offers fits worse (the room turned half way round still fits its
    // outer walls, four fifths of the wall length), and they come best first.
    if (places.size() > 1) {
      EXPECT_LT(places[1].score, 0.9 * places[0].score);
    }
    for (size_t i = 1; i < places.size(); ++i) EXPECT_LE(places[i].score, places[i - 1].score);
    EXPECT_GT(stats.rotations, 100u);
    EXPECT_LE(stats.points, 400u);
  }
}

TEST(GlobalSearchTest, OffersEveryRoomThatLooksTheSame) {
  // Six identical rooms either side of a corridor: one room's walls fit all of them, and
  // each of them turned half way round (a door in the middle of a wall).
  const FloorPlan plan = testing::SyntheticOffice(6);
  GlobalSearchOptions options;
  options.places = 6;
  const GlobalSearch search(plan, options);
  SplitMix64 rng(5);
  const Se2 T_slam_plan{0.6, {3.0, -7.0}};
  const Eigen::Vector2d room_centre(12.5, 4.0);  // the room north of the corridor, x 10..15
  const Box window{{9.9, 1.9}, {15.1, 6.1}};
  testing::ScanOptions o;
  o.noise_m = 0.02;
  const testing::Scan scan = MakeScan(plan, window, T_slam_plan, o, rng);
  // Where a place puts the room seen: on the centre of some room, else nowhere.
  auto on_a_room = [&](const GlobalPlace& p) {
    const Eigen::Vector2d c = p.T_plan_slam * (T_slam_plan * room_centre);
    for (int i = 0; i < 6; ++i)
      for (const double y : {4.0, -2.0})
        if ((c - Eigen::Vector2d(2.5 + 5 * i, y)).norm() < 0.2) return true;
    return false;
  };
  const std::vector<GlobalPlace> places = search.Search(scan.points);
  ASSERT_EQ(places.size(), 6u);
  for (const GlobalPlace& p : places) {
    EXPECT_TRUE(on_a_room(p)) << p.T_plan_slam.t.transpose() << " " << p.T_plan_slam.theta;
    EXPECT_GT(p.score, 0.9 * places[0].score) << "the rooms fit alike";
  }
  // At the true heading, only the six rooms north of the corridor have their door on the
  // south: those are the places, the true one among them, each a room apart.
  const double heading = T_slam_plan.Inverse().theta;
  const std::vector<GlobalPlace> north = search.Search(scan.points, {heading});
  ASSERT_EQ(north.size(), 6u);
  bool truth_offered = false;
  for (const GlobalPlace& p : north) {
    EXPECT_TRUE(on_a_room(p));
    EXPECT_GT((p.T_plan_slam * (T_slam_plan * room_centre)).y(), 3.0);
    truth_offered = truth_offered ||
                    ErrorAt(p.T_plan_slam, T_slam_plan.Inverse(), room_centre).translation_m < 0.2;
  }
  EXPECT_TRUE(truth_offered);
}

TEST(GlobalSearchTest, NoTranslationOnItsGridBeatsIt) {
  // Brute force over every translation of the grid at the true heading must not beat it.
  const FloorPlan plan = testing::AsymmetricRoom();
  GlobalSearchOptions options;
  options.max_points = 100000;  // keep every point: 25 cm apart, one a cell
  options.places = 1;
  const GlobalSearch search(plan, options);
  const Se2 T_plan_slam{0.3, {2.0, 1.0}};
  std::vector<Eigen::Vector2d> cloud;
  for (const Eigen::Vector2d& p : testing::SampleWalls(plan, 0.25))
    if (p.x() < 6.5) cloud.push_back(T_plan_slam.Inverse() * p);
  const std::vector<GlobalPlace> best = search.Search(cloud, {T_plan_slam.theta});
  ASSERT_EQ(best.size(), 1u);
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& p : cloud) centre += p;
  centre /= static_cast<double>(cloud.size());
  const GridGeometry& g = search.grid();
  const Se2 rotate{T_plan_slam.theta, Eigen::Vector2d::Zero()};
  double brute = 0;
  for (int cell = 0; cell < static_cast<int>(g.size()); ++cell)
    brute = std::max(
        brute, search.Score(cloud, Se2{T_plan_slam.theta, g.CellCentre(cell) - rotate * centre}));
  // Equal up to a point landing on the other side of a cell edge by rounding (Score goes
  // through the transform, the search through integer cell offsets).
  const double one_point = 1.0 / static_cast<double>(cloud.size());
  EXPECT_GE(best[0].score, brute - one_point);
  EXPECT_NEAR(search.Score(cloud, best[0].T_plan_slam), best[0].score, one_point);
  EXPECT_LT((best[0].T_plan_slam.t - T_plan_slam.t).norm(), 0.1);
}

TEST(GlobalSearchTest, HeadingsCanBeNarrowedToCandidates) {
  const FloorPlan plan = testing::AsymmetricRoom();
  const GlobalSearch search(plan);
  SplitMix64 rng(9);
  const Se2 T_slam_plan{-2.0, {8.0, 3.0}};
  const testing::Scan scan =
      MakeScan(plan, Box::Around({5, 3.5}, 12), T_slam_plan, testing::ScanOptions{}, rng);
  const double truth = T_slam_plan.Inverse().theta;
  GlobalSearchStats stats;
  const auto near = search.Search(scan.points, {truth - 0.01, truth, truth + 0.01}, &stats);
  EXPECT_EQ(stats.rotations, 3u);
  ASSERT_FALSE(near.empty());
  EXPECT_LT(ErrorAt(near[0].T_plan_slam, T_slam_plan.Inverse(), {5, 3.5}).translation_m, 0.1);
  // Turned a quarter away, the room fits far worse (if at all).
  const auto wrong = search.Search(scan.points, {truth + M_PI / 2});
  if (!wrong.empty()) {
    EXPECT_LT(wrong[0].score, 0.7 * near[0].score);
  }
}

TEST(GlobalSearchTest, TheWallsDirectionsNarrowTheHeadingsToAFew) {
  const FloorPlan plan = testing::AsymmetricRoom();
  const GlobalSearch search(plan);
  SplitMix64 rng(11);
  const testing::ScanOptions o = NoisyCluttered();
  for (int trial = 0; trial < 6; ++trial) {
    const Se2 T_slam_plan = testing::RandomSe2(rng, M_PI, 50.0);  // anywhere, any heading
    const testing::Scan scan = MakeScan(plan, Box::Around({5, 3.5}, 12), T_slam_plan, o, rng);
    const std::vector<double> headings = search.WallHeadings(scan.points);
    ASSERT_FALSE(headings.empty());
    GlobalSearchStats all, narrowed;
    const auto full = search.Search(scan.points, {}, &all);
    const auto fast = search.Search(scan.points, headings, &narrowed);
    ASSERT_FALSE(fast.empty());
    EXPECT_LT(narrowed.rotations * 4, all.rotations);
    // The same place as the search over every heading.
    ASSERT_FALSE(full.empty());
    const auto e = ErrorAt(fast[0].T_plan_slam, full[0].T_plan_slam, {5, 3.5});
    EXPECT_LT(e.translation_m, 0.15) << "trial " << trial << ": " << testing::Describe(e);
    EXPECT_LT(e.rotation_rad, testing::Deg(1.0)) << "trial " << trial;
  }
  // Points with no straight wall in them suggest nothing.
  EXPECT_TRUE(search.WallHeadings({{0, 0}, {5, 5}, {NAN, 0}}).empty());
}

TEST(GlobalSearchTest, NothingToFindInNothing) {
  const GlobalSearch search(testing::AsymmetricRoom());
  EXPECT_TRUE(search.Search({}).empty());
  EXPECT_TRUE(search.Search({{NAN, 1.0}, {1.0, INFINITY}, {1e300, 0}}).empty());
  // Points nowhere near any wall shape: no place reaches min_score.
  SplitMix64 rng(1);
  std::vector<Eigen::Vector2d> fog;
  for (int i = 0; i < 300; ++i) fog.push_back({rng.Uniform(0, 40), rng.Uniform(0, 40)});
  const auto places = search.Search(fog);
  for (const GlobalPlace& p : places) EXPECT_LT(p.score, 0.5);
  EXPECT_LT(search.MemoryBytes(), size_t{20} << 20);
}

TEST(GlobalSearchTest, RefinedPlacesFitToCentimetresAndComeBestFirst) {
  const FloorPlan plan = testing::AsymmetricRoom();
  const GlobalSearch search(plan);
  const ClosestWallIndex index(plan);
  SplitMix64 rng(11);
  const testing::ScanOptions o = NoisyCluttered();
  for (int trial = 0; trial < 4; ++trial) {
    const Se2 T_slam_plan = testing::RandomSe2(rng, M_PI, 50.0);
    const Box window = Box::Around({5, 3.5}, 12);
    const testing::Scan scan = MakeScan(plan, window, T_slam_plan, o, rng);
    const std::vector<GlobalPlace> places = search.Search(scan.points);
    ASSERT_FALSE(places.empty());
    const std::vector<GlobalPlace> refined =
        RefinePlaces(places, scan.points, {}, index, IcpOptions{});
    ASSERT_FALSE(refined.empty());
    EXPECT_LE(refined.size(), places.size());
    const auto e = ErrorAt(refined[0].T_plan_slam, T_slam_plan.Inverse(), window.Centre());
    EXPECT_LT(e.translation_m, 0.05) << "trial " << trial << ": " << testing::Describe(e);
    EXPECT_LT(e.rotation_rad, testing::Deg(0.5)) << "trial " << trial;
    // Four fifths of the points are walls with 3 cm of noise: they fit.
    EXPECT_GT(refined[0].inlier_ratio, 0.75);
    for (size_t i = 1; i < refined.size(); ++i) {
      EXPECT_GE(refined[i].fit_mse, refined[i - 1].fit_mse);
      // Merged: no two places left on top of each other.
      EXPECT_GT(
          (refined[i].T_plan_slam.t - refined[0].T_plan_slam.t).norm() +
              std::abs(WrapAngle(refined[i].T_plan_slam.theta - refined[0].T_plan_slam.theta)),
          0.1);
    }
    // Places refined already are ranked again with new ones, not refined again: the same
    // places come back, in the same order, with the same fits.
    const std::vector<GlobalPlace> again =
        RefinePlaces({}, scan.points, {}, index, IcpOptions{}, {}, refined);
    ASSERT_EQ(again.size(), refined.size());
    for (size_t i = 0; i < again.size(); ++i) {
      EXPECT_EQ(again[i].fit_mse, refined[i].fit_mse) << i;
      EXPECT_EQ(again[i].T_plan_slam.t, refined[i].T_plan_slam.t) << i;
    }
  }
  // Nothing in, nothing out; non-finite points are ignored.
  EXPECT_TRUE(RefinePlaces({}, {}, {}, index, IcpOptions{}).empty());
  EXPECT_TRUE(
      RefinePlaces({GlobalPlace{}}, {Eigen::Vector2d(NAN, 0)}, {}, index, IcpOptions{}).empty());
}

// Room 2 of testing::SyntheticOffice (north of the corridor, x 10-15 m), scanned into
// the slam frame with 2 cm of noise.
const Box kOfficeRoom2{{9.9, 1.9}, {15.1, 6.1}};
testing::Scan ScanOfficeRoom2(const FloorPlan& plan, const Se2& T_slam_plan, uint64_t seed) {
  SplitMix64 rng(seed);
  testing::ScanOptions o;
  o.noise_m = 0.02;
  return MakeScan(plan, kOfficeRoom2, T_slam_plan, o, rng);
}

TEST(GlobalSearchTest, PlacesThatWalkTheWearerThroughWallsGoLast) {
  // Twelve identical rooms; the wearer came along the corridor from 8 m west of room 2's
  // door, then into the room. Its walls fit every room, but only in some of them does the
  // walk through the corridor stay clear of walls: not in rooms 0 and 1 (the corridor's
  // west end is in the way), nor in the south rooms turned round near the east end.
  const FloorPlan plan = testing::SyntheticOffice(6);
  GlobalSearchOptions options;
  options.places = 12;
  const GlobalSearch search(plan, options);
  const ClosestWallIndex index(plan);
  const Se2 T_slam_plan{0.6, {3.0, -7.0}};
  const Box window = kOfficeRoom2;
  const testing::Scan scan = ScanOfficeRoom2(plan, T_slam_plan, 7);
  std::vector<Eigen::Vector2d> path;
  for (double x = 4.5; x <= 12.5; x += 0.25) path.push_back(T_slam_plan * Eigen::Vector2d(x, 1.0));
  for (double y = 1.25; y <= 4.0; y += 0.25) path.push_back(T_slam_plan * Eigen::Vector2d(12.5, y));
  const std::vector<GlobalPlace> places = search.Search(scan.points);
  const IcpOptions icp;
  const auto everywhere = RefinePlaces(places, scan.points, {}, index, icp);
  const auto walkable = RefinePlaces(places, scan.points, path, index, icp);
  ASSERT_GE(everywhere.size(), 10u);
  ASSERT_EQ(walkable.size(), everywhere.size());
  // The places whose walk stays clear of walls come first, then the others.
  const auto clear_end = std::find_if(walkable.begin(), walkable.end(),
                                      [](const GlobalPlace& p) { return p.path_crossings > 0; });
  EXPECT_GE(walkable.end() - clear_end, 3);
  EXPECT_TRUE(std::all_of(clear_end, walkable.end(),
                          [](const GlobalPlace& p) { return p.path_crossings > 0; }));
  bool truth_kept = false;
  for (auto it = walkable.begin(); it != clear_end; ++it) {
    const GlobalPlace& p = *it;
    const Eigen::Vector2d start = p.T_plan_slam * path.front();
    EXPECT_GT(start.x(), 0.0) << "the walk would start west of the building";
    truth_kept = truth_kept ||
                 ErrorAt(p.T_plan_slam, T_slam_plan.Inverse(), window.Centre()).translation_m < 0.1;
  }
  EXPECT_TRUE(truth_kept);
}

TEST(GlobalSearchTest, APlaceOffTheWallsGoesLastHoweverClearItsWalk) {
  // The wearer is in room 2 of the office, and the SLAM's path (drifted) runs through the
  // wall to room 3 once. A place 40 m north, outside the building, walks them through no
  // wall at all, but fits none of the walls: it must not come first on its walk.
  const FloorPlan plan = testing::SyntheticOffice(6);
  const ClosestWallIndex index(plan);
  const Se2 T_slam_plan{0.4, {-2.0, 5.0}};
  const Box window = kOfficeRoom2;
  const testing::Scan scan = ScanOfficeRoom2(plan, T_slam_plan, 11);
  std::vector<Eigen::Vector2d> path;
  for (double x = 12.5; x <= 16.0; x += 0.25) path.push_back(T_slam_plan * Eigen::Vector2d(x, 4.0));
  const Se2 truth = T_slam_plan.Inverse();
  const Se2 outside = Se2{0, {0, 40}} * truth;
  const std::vector<GlobalPlace> places = {{outside}, {truth}};
  const IcpOptions icp;
  RefineOptions options;
  options.path_margin_m = 0.4;

  // On the walk alone (no min_inliers), the place outside comes first: fewer crossings.
  const auto by_walk = RefinePlaces(places, scan.points, path, index, icp, options);
  ASSERT_EQ(by_walk.size(), 2u);
  EXPECT_EQ(by_walk[0].path_crossings, 0u);
  EXPECT_EQ(by_walk[1].path_crossings, 1u);
  EXPECT_EQ(by_walk[1].rank, 1);

  // Fitting first: the room, rank 0; the place outside, fitting nothing, rank 2.
  options.min_inliers = 0.6;
  const auto by_fit = RefinePlaces(places, scan.points, path, index, icp, options);
  ASSERT_EQ(by_fit.size(), 2u);
  EXPECT_LT(ErrorAt(by_fit[0].T_plan_slam, truth, window.Centre()).translation_m, 0.05);
  EXPECT_GT(by_fit[0].inlier_ratio, 0.9);
  EXPECT_EQ(by_fit[0].rank, 0);
  EXPECT_EQ(by_fit[1].inlier_ratio, 0.0);
  EXPECT_EQ(by_fit[1].rank, 2);

  // Without the margin, the same walk crossing mid-wall counts alike.
  options.path_margin_m = 0;
  EXPECT_EQ(RefinePlaces(places, scan.points, path, index, icp, options)[0].path_crossings, 1u);
}

TEST(GlobalSearchTest, APlaceWhoseWallsTheWearerCouldNotHaveSeenFitsWorse) {
  // Rooms 4 m and 2 m wide (walls at x = 4 and 6). The wearer walked 3 m west of the wall
  // at x = 4 and saw it. The same wall 2 m east fits the plan's wall at x = 6 as well,
  // and the walk there (x = 3) crosses nothing; but from there the wall at x = 4 stands
  // between the wearer and every point seen.
  auto parse = MakeFloorPlan("rooms", {{{0, 0}, {12, 0}},
                                       {{12, 0}, {12, 7}},
                                       {{12, 7}, {0, 7}},
                                       {{0, 7}, {0, 0}},
                                       {{4, 0}, {4, 7}},
                                       {{6, 0}, {6, 7}}});
  ASSERT_TRUE(parse.ok()) << parse.error;
  const ClosestWallIndex index(parse.plan);
  std::vector<Eigen::Vector2d> seen, path;
  for (double y = 1; y <= 6; y += 0.1) seen.emplace_back(4, y);
  for (double y = 1; y <= 6; y += 0.25) path.emplace_back(1, y);
  const Se2 truth{0, {0, 0}}, behind{0, {2, 0}};
  const std::vector<GlobalPlace> places = {{behind}, {truth}};
  RefineOptions options;
  const auto blind = RefinePlaces(places, seen, path, index, IcpOptions{}, options);
  ASSERT_EQ(blind.size(), 2u);
  EXPECT_NEAR(blind[0].fit_mse, blind[1].fit_mse, 1e-6);  // both fit, both walk clear
  options.sight_reach_m = 4.5;
  const auto sighted = RefinePlaces(places, seen, path, index, IcpOptions{}, options);
  ASSERT_EQ(sighted.size(), 2u);
  EXPECT_LT((sighted[0].T_plan_slam.t - truth.t).norm(), 0.05);
  EXPECT_EQ(sighted[0].hidden_ratio, 0.0);
  EXPECT_EQ(sighted[1].hidden_ratio, 1.0);
  // Every point a miss, less the share allowed for drift.
  EXPECT_NEAR(sighted[1].fit_mse - sighted[0].fit_mse,
              (1 - options.sight_allowance) * options.cap_m * options.cap_m, 1e-6);
  EXPECT_EQ(sighted[0].rank, 0);
  EXPECT_EQ(sighted[1].rank, 0);
}

TEST(GlobalSearchTest, APlaceThatWalksTheWearerPastWallsNobodySawFitsWorse) {
  // Two rooms with the same west wall: x = 0 (a room 5 m wide) and x = 10 (a corridor
  // 1.5 m wide, its east wall at x = 11.5). The wearer walked 1 m east of the west wall
  // and saw it, nothing else: in the room the east wall is out of reach, in the
  // corridor it is 0.5 m away and nobody saw it (the whole of it in sight: 2 m or
  // less from the walk).
  auto parse = MakeFloorPlan(
      "look-alikes",
      {{{0, 0}, {0, 8}}, {{5, 0}, {5, 8}}, {{10, 0}, {10, 8}}, {{11.5, 0}, {11.5, 8}}});
  ASSERT_TRUE(parse.ok()) << parse.error;
  const ClosestWallIndex index(parse.plan);
  std::vector<Eigen::Vector2d> seen, path;
  for (double y = 0; y <= 8; y += 0.1) seen.emplace_back(0, y);
  for (double y = 1; y <= 7; y += 0.25) path.emplace_back(1, y);
  const Se2 truth{0, {0, 0}}, corridor{0, {10, 0}};
  const std::vector<GlobalPlace> places = {{corridor}, {truth}};
  RefineOptions options;
  const auto blind = RefinePlaces(places, seen, path, index, IcpOptions{}, options);
  ASSERT_EQ(blind.size(), 2u);
  EXPECT_NEAR(blind[0].fit_mse, blind[1].fit_mse, 1e-6);  // both fit, both walk clear
  options.unseen_reach_m = 2.0;
  const auto checked = RefinePlaces(places, seen, path, index, IcpOptions{}, options);
  ASSERT_EQ(checked.size(), 2u);
  const auto at = [&](const std::vector<GlobalPlace>& p, const Se2& T) {
    return (p[0].T_plan_slam.t - T.t).norm() < 0.05 ? p[0] : p[1];
  };
  EXPECT_EQ(at(checked, truth).unseen_ratio, 0.0);
  EXPECT_NEAR(at(checked, corridor).unseen_ratio, 0.5, 0.05);  // the east wall of two
  EXPECT_GT(at(checked, corridor).unseen_expected, options.unseen_min_samples);
  // Half missed is within the allowance: no cost. With none allowed, half a miss a point.
  EXPECT_NEAR(checked[0].fit_mse, checked[1].fit_mse, 1e-6);
  options.unseen_allowance = 0;
  const auto strict = RefinePlaces(places, seen, path, index, IcpOptions{}, options);
  ASSERT_EQ(strict.size(), 2u);
  EXPECT_LT((strict[0].T_plan_slam.t - truth.t).norm(), 0.05);
  EXPECT_NEAR(strict[1].fit_mse - strict[0].fit_mse,
              options.unseen_weight * strict[1].unseen_ratio * options.cap_m * options.cap_m, 1e-6);
  // A place that misses more than unseen_max_ratio of the walls it walks past does not
  // fit at all, however its points lie: last, with rank 2.
  EXPECT_EQ(strict[1].rank, 0);
  options.unseen_max_ratio = 0.4;
  const auto gated = RefinePlaces(places, seen, path, index, IcpOptions{}, options);
  ASSERT_EQ(gated.size(), 2u);
  EXPECT_LT((gated[0].T_plan_slam.t - truth.t).norm(), 0.05);
  EXPECT_EQ(gated[0].rank, 0);
  EXPECT_EQ(gated[1].rank, 2);
}

TEST(GlobalSearchTest, ARoomAndItsHalfTurnLookAlikeFromTheWalkUnlessAPartitionTellsThemApart) {
  // A room 10 x 6 m, walked along its middle (x 3..7, y 3; slam = plan under `a`). Half
  // a turn about its centre, `b`, the walk passes the same walls: alike.
  const std::vector<Segment> room = {
      {{0, 0}, {10, 0}}, {{10, 0}, {10, 6}}, {{10, 6}, {0, 6}}, {{0, 6}, {0, 0}}};
  auto parse = MakeFloorPlan("room", room);
  ASSERT_TRUE(parse.ok()) << parse.error;
  const ClosestWallIndex index(parse.plan);
  std::vector<Eigen::Vector2d> path;
  for (double x = 3; x <= 7; x += 0.25) path.emplace_back(x, 3);
  const Se2 a{0, {0, 0}}, b{M_PI, {10, 6}};
  const PlanAlikeness same = PlanAlike(path, a, b, index, 4.5);
  EXPECT_GT(same.samples, 80u);
  EXPECT_GT(same.share, 0.99);
  // HalfTurnTwins finds b from a, with the plan's walls in sight of the walk.
  WallSampleOptions in_sight;
  in_sight.reach_m = 4.5;
  const GlobalSearch search(parse.plan);
  const std::vector<GlobalPlace> twins = HalfTurnTwins(search, parse.plan, a, path, {}, in_sight);
  ASSERT_FALSE(twins.empty());
  EXPECT_LT((twins[0].T_plan_slam * Eigen::Vector2d(5, 3) - Eigen::Vector2d(5, 3)).norm(), 0.2);
  EXPECT_LT(std::abs(WrapAngle(twins[0].T_plan_slam.theta - M_PI)), 0.05);
  EXPECT_TRUE(HalfTurnTwins(search, parse.plan, a, {}, {}, in_sight).empty());  // no walk
  // RefinePlaces compares the places after the first with it (on the room's walls, both
  // fit and walk clear).
  std::vector<Eigen::Vector2d> seen;
  for (double x = 0; x <= 10; x += 0.1) seen.emplace_back(x, 0), seen.emplace_back(x, 6);
  RefineOptions options;
  options.alike_reach_m = 4.5;
  const auto refined = RefinePlaces({{a}, {b}}, seen, path, index, IcpOptions{}, options);
  ASSERT_EQ(refined.size(), 2u);
  EXPECT_EQ(refined[0].alike, -1);
  EXPECT_GT(refined[1].alike, 0.99);
  // A partition 1 m east of the walk's end (x = 8, y 1..5) is not there half a turn
  // away, and it hides part of the east wall: the walk tells the two apart.
  auto walled = room;
  walled.push_back({{8, 1}, {8, 5}});
  parse = MakeFloorPlan("room with a partition", walled);
  ASSERT_TRUE(parse.ok()) << parse.error;
  const ClosestWallIndex walled_index(parse.plan);
  const PlanAlikeness different = PlanAlike(path, a, b, walled_index, 4.5);
  EXPECT_GT(different.samples, 60u);
  EXPECT_LT(different.share, 0.9);
  EXPECT_GT(different.share, 0.5);
  // No walk, nothing in sight: nothing alike.
  const PlanAlikeness none = PlanAlike({}, a, b, index, 4.5);
  EXPECT_EQ(none.samples, 0u);
  EXPECT_EQ(none.share, 0.0);
}

TEST(GlobalSearchTest, InAHallOfRepeatedBaysThePlacesAsGoodKeepComing) {
  // Eight square rooms in a row, 4 m each: the walls of one fit every room at four
  // headings. Four places come back, or, with a crowd ratio, up to crowd_places, all
  // scoring as well as the best.
  std::vector<Segment> walls = {{{0, 0}, {32, 0}}, {{0, 4}, {32, 4}}};
  for (double x = 0; x <= 32; x += 4) walls.push_back({{x, 0}, {x, 4}});
  auto parse = MakeFloorPlan("bays", walls);
  ASSERT_TRUE(parse.ok()) << parse.error;
  std::vector<Eigen::Vector2d> room;
  for (double t = 0.1; t < 4; t += 0.1) {
    room.emplace_back(8 + t, 0), room.emplace_back(8 + t, 4);
    room.emplace_back(8, t), room.emplace_back(12, t);
  }
  GlobalSearchOptions options;
  const GlobalSearch few(parse.plan, options);
  EXPECT_EQ(few.max_places(), options.places);
  EXPECT_EQ(few.Search(room).size(), options.places);
  options.crowd_ratio = 0.98;
  const GlobalSearch crowd(parse.plan, options);
  EXPECT_EQ(crowd.max_places(), options.crowd_places);
  const std::vector<GlobalPlace> places = crowd.Search(room);
  ASSERT_EQ(places.size(), options.crowd_places);
  for (const GlobalPlace& p : places) EXPECT_GE(p.score, 0.98 * places.front().score);
  // A room unlike the others (a partition across its middle, which the walls seen show)
  // fits only itself, both ways round: the places after those two score less, and no
  // more than `places` come back.
  walls.push_back({{10, 1}, {10, 3}});
  parse = MakeFloorPlan("bays and a partition", walls);
  ASSERT_TRUE(parse.ok()) << parse.error;
  for (double y = 1.1; y < 3; y += 0.1) room.emplace_back(10, y);
  const GlobalSearch one(parse.plan, options);
  const std::vector<GlobalPlace> unique = one.Search(room);
  ASSERT_EQ(unique.size(), options.places);
  EXPECT_LT(unique.back().score, 0.98 * unique.front().score);
  for (int i = 0; i < 2; ++i) {  // the room itself, and its half-turn about (10, 2)
    EXPECT_LT((unique[i].T_plan_slam * Eigen::Vector2d(10, 2) - Eigen::Vector2d(10, 2)).norm(),
              0.3);
    EXPECT_LT(std::abs(std::sin(unique[i].T_plan_slam.theta)), 0.1);
  }
}

}  // namespace
}  // namespace floorpose
