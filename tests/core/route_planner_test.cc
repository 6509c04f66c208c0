#include "core/route_planner.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/random.h"
#include "core/rooms.h"
#include "tests/route_test_util.h"
#include "tests/sim_test_plans.h"

namespace floorpose {
namespace {

using testing::BruteForceShortest;
using testing::PathClearance;
using testing::SyntheticOffice;

// Every leg clear of the walls by the body radius, and the length near brute force.
void ExpectGoodRoute(const FloorPlan& plan, const RoutePlanner& planner, const Route& route,
                     const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
  ASSERT_TRUE(route.ok()) << route.error;
  ASSERT_GE(route.path.size(), 2u);
  EXPECT_EQ(route.path.front(), from);
  EXPECT_EQ(route.path.back(), to);
  EXPECT_GE(PathClearance(route.path, plan.segments), planner.options().body_radius_m - 1e-9);
  EXPECT_NEAR(route.length_m, PolylineLength(route.path), 1e-9);
  const testing::Reference ref = BruteForceShortest(planner, from, to);
  EXPECT_LE(route.length_m, 1.05 * ref.centres_m + ref.ends_m) << "brute force " << ref.centres_m;
  // Not shorter than the shortest: the reference is at most 1.3% above it.
  EXPECT_GE(route.length_m, ref.centres_m / 1.013 - ref.ends_m - 1e-9)
      << "brute force " << ref.centres_m;
}

TEST(RoutePlannerTest, CrossesTheCorridorThroughBothDoors) {
  const FloorPlan plan = SyntheticOffice(4);
  const RoutePlanner planner(plan);
  // From the middle of a north room to the middle of the south room two doors east.
  const Eigen::Vector2d from(2.5, 4.0), to(12.5, -2.0);
  const Route route = planner.Plan(from, to);
  ExpectGoodRoute(plan, planner, route, from, to);
  // Through the north door of room 0 (x 2..3 at y 2) and the south door of room 2.
  bool north_door = false, south_door = false;
  for (size_t i = 1; i < route.path.size(); ++i) {
    const Eigen::Vector2d a = route.path[i - 1], b = route.path[i];
    for (double t = 0; t <= 1; t += 0.01) {
      const Eigen::Vector2d p = a + t * (b - a);
      if (std::abs(p.y() - 2) < 0.02) north_door |= p.x() > 2 && p.x() < 3;
      if (std::abs(p.y()) < 0.02) south_door |= p.x() > 12 && p.x() < 13;
    }
  }
  EXPECT_TRUE(north_door);
  EXPECT_TRUE(south_door);
  // A straight line would be 11.7 m; the doors make it longer, the corners few.
  EXPECT_GT(route.length_m, (to - from).norm());
  EXPECT_LE(route.path.size(), 8u);
}

TEST(RoutePlannerTest, RandomPairsAreClearAndNearlyShortest) {
  const FloorPlan plan = SyntheticOffice(3, 12.0);
  const RoutePlanner planner(plan);
  const RoomMap rooms(plan);  // indoors: every room is reachable through its door
  SplitMix64 rng(7);
  int checked = 0;
  for (int attempt = 0; attempt < 200 && checked < 12; ++attempt) {
    const Eigen::Vector2d a(rng.Uniform(plan.min.x(), plan.max.x()),
                            rng.Uniform(plan.min.y(), plan.max.y()));
    const Eigen::Vector2d b(rng.Uniform(plan.min.x(), plan.max.x()),
                            rng.Uniform(plan.min.y(), plan.max.y()));
    if (!planner.Passable(planner.grid().CellOf(a)) ||
        !planner.Passable(planner.grid().CellOf(b)) || rooms.RoomAt(a) < 0 || rooms.RoomAt(b) < 0)
      continue;
    SCOPED_TRACE(::testing::Message() << "from " << a.transpose() << " to " << b.transpose());
    ExpectGoodRoute(plan, planner, planner.Plan(a, b), a, b);
    ++checked;
  }
  EXPECT_EQ(checked, 12);
}

TEST(RoutePlannerTest, RefusesClearly) {
  FloorPlan plan = SyntheticOffice(2);
  // Seal the door of the first north room (x 2..3 at y 2).
  plan.segments.push_back({{2, 2}, {3, 2}});
  const RoutePlanner planner(plan);
  const Eigen::Vector2d corridor(5.0, 1.0);
  const Route sealed = planner.Plan(corridor, {2.5, 4.0});
  EXPECT_FALSE(sealed.ok());
  EXPECT_NE(sealed.error.find("no path"), std::string::npos) << sealed.error;
  EXPECT_NE(planner.Plan(corridor, {50, 1}).error.find("outside the plan"), std::string::npos);
  EXPECT_NE(planner.Plan({NAN, 0}, corridor).error.find("NaN"), std::string::npos);
  // Too wide for the doors (1 m): the rooms are out of reach, the corridor is not.
  RouteOptions wide;
  wide.body_radius_m = 0.55;
  const RoutePlanner broad(plan, wide);
  EXPECT_FALSE(broad.Plan(corridor, {7.5, -2.0}).ok());
  EXPECT_TRUE(broad.Plan(corridor, {8.0, 1.0}).ok());
}

TEST(RoutePlannerTest, AWearerAtAWallStartsWhereTheyStand) {
  const FloorPlan plan = SyntheticOffice(2);
  const RoutePlanner planner(plan);
  const Eigen::Vector2d at_wall(4.0, 1.9);  // 0.1 m from the corridor's north wall
  const Route route = planner.Plan(at_wall, {7.5, -2.0});
  ASSERT_TRUE(route.ok()) << route.error;
  EXPECT_EQ(route.path.front(), at_wall);
  EXPECT_GT(route.start_moved_m, 0.15);
  EXPECT_LT(route.start_moved_m, 0.35);
  // After leaving the wall, the route keeps the body radius.
  const std::vector<Eigen::Vector2d> rest(route.path.begin() + 1, route.path.end());
  EXPECT_GE(PathClearance(rest, plan.segments), 0.3 - 1e-9);
  // A destination picked on a wall ends next to it.
  const Route to_wall = planner.Plan({4.0, 1.0}, {7.5, 6.0});
  ASSERT_TRUE(to_wall.ok()) << to_wall.error;
  EXPECT_GT(to_wall.goal_moved_m, 0.3);
  EXPECT_LT(to_wall.goal_moved_m, 0.45);
}

TEST(RoutePlannerTest, SameRequestSameRoute) {
  const FloorPlan plan = SyntheticOffice(3);
  const RoutePlanner a(plan), b(plan);
  const Route ra = a.Plan({1, 1}, {13.5, 5}), rb = b.Plan({1, 1}, {13.5, 5});
  ASSERT_TRUE(ra.ok());
  EXPECT_EQ(ra.path, rb.path);
}

}  // namespace
}  // namespace floorpose
