// What the daemon does for a wearer in trouble: the no-motion alert, the way back and
// routes that keep out of hazards and blocked exits.
#include <gtest/gtest.h>

#include <cmath>

#include "core/breadcrumbs.h"
#include "core/no_motion.h"
#include "core/route_planner.h"
#include "tests/route_test_util.h"
#include "tests/sim_test_plans.h"

namespace floorpose {
namespace {

using testing::PathClearance;
using testing::SyntheticOffice;

// The closest the path comes to the centre of k.
double ClosestTo(const std::vector<Eigen::Vector2d>& path, const KeepOut& k) {
  double closest = INFINITY;
  for (size_t i = 1; i < path.size(); ++i)
    closest = std::min(closest,
                       (ClosestPointOnSegment({path[i - 1], path[i]}, k.centre) - k.centre).norm());
  return closest;
}

constexpr int64_t kSecond = 1'000'000'000;

TEST(NoMotionAlarmTest, PreAlertAtTwentySecondsAlertAtThirtyClearedByMoving) {
  NoMotionAlarm alarm({0.3, 20.0, 30.0});
  const Eigen::Vector3d head(1, 2, 1.6);
  int changes = 0;
  // Breathing and a slumped head: centimetres, for 31 s of poses 0.3 s apart.
  for (int i = 0; i * 0.3 <= 31.0; ++i) {
    const double t = i * 0.3;
    changes += alarm.Update(static_cast<int64_t>(t * kSecond),
                            head + Eigen::Vector3d(0.05 * std::sin(t), 0.03, 0.04 * std::cos(t)));
    const NoMotionAlarm::Level want = t >= 30.0   ? NoMotionAlarm::Level::kAlert
                                      : t >= 20.0 ? NoMotionAlarm::Level::kPreAlert
                                                  : NoMotionAlarm::Level::kNone;
    ASSERT_EQ(alarm.level(), want) << "at " << t << " s";
  }
  EXPECT_EQ(changes, 2);
  EXPECT_NEAR(alarm.still_s(), 30.9, 0.31);
  EXPECT_TRUE(alarm.Acknowledge("lead"));
  EXPECT_TRUE(alarm.acknowledged());
  EXPECT_EQ(alarm.acknowledged_by(), "lead");
  // Still no motion: acknowledged, still in alert.
  EXPECT_FALSE(alarm.Update(32 * kSecond, head));
  EXPECT_EQ(alarm.level(), NoMotionAlarm::Level::kAlert);
  // A step ends the episode and its acknowledgement.
  EXPECT_TRUE(alarm.Update(33 * kSecond, head + Eigen::Vector3d(0.5, 0, 0)));
  EXPECT_EQ(alarm.level(), NoMotionAlarm::Level::kNone);
  EXPECT_FALSE(alarm.acknowledged());
  EXPECT_FALSE(alarm.Acknowledge("lead")) << "nothing to acknowledge";
}

TEST(NoMotionAlarmTest, WalkingSlowlyNeverAlerts) {
  NoMotionAlarm alarm;
  // 0.1 m/s, a searcher crawling: 3 cm a pose, out of the radius every 4 s.
  for (int i = 0; i < 400; ++i) {
    alarm.Update(static_cast<int64_t>(i * 0.3 * kSecond), {0.03 * i, 0, 0.5});
    ASSERT_EQ(alarm.level(), NoMotionAlarm::Level::kNone) << i;
  }
  EXPECT_LT(alarm.still_s(), 4.0);
}

TEST(BreadcrumbsTest, KeepsTheWholeWalkInBoundedMemory) {
  Breadcrumbs crumbs(0.5, 64);
  for (int i = 0; i <= 1000; ++i) crumbs.Add({0.1 * i, 0}, "0");  // 100 m
  EXPECT_LE(crumbs.crumbs().size(), 64u);
  EXPECT_GT(crumbs.spacing(), 0.5);
  EXPECT_EQ(crumbs.crumbs().front().slam, Eigen::Vector2d(0, 0)) << "the entry is kept";
  for (size_t i = 1; i < crumbs.crumbs().size(); ++i)
    EXPECT_LE((crumbs.crumbs()[i].slam - crumbs.crumbs()[i - 1].slam).norm(),
              crumbs.spacing() + 0.1 + 1e-9);
  EXPECT_NEAR(crumbs.crumbs().back().slam.x(), 100.0, crumbs.spacing());
}

TEST(BreadcrumbsTest, TheWayBackOnAFloorEndsWhereTheWearerCameOntoIt) {
  Breadcrumbs crumbs;
  for (int i = 0; i <= 20; ++i) crumbs.Add({0.5 * i, 0}, "0");
  for (int i = 0; i <= 10; ++i) crumbs.Add({10, 0.5 * i}, "1");
  const std::vector<Eigen::Vector2d> back = crumbs.WayBackOn("1");
  ASSERT_EQ(back.size(), 11u);
  EXPECT_EQ(back.front(), Eigen::Vector2d(10, 5)) << "newest first";
  EXPECT_EQ(back.back(), Eigen::Vector2d(10, 0)) << "where floor 1 began";
  EXPECT_EQ(crumbs.WayBackOn("0").size(), 0u) << "the wearer is not on floor 0 now";
  crumbs.Add({10.1, 5}, "1");
  EXPECT_EQ(crumbs.crumbs().size(), 32u) << "closer than the spacing: not kept";
}

TEST(KeepOutTest, RoutesGoRoundAHazardAndRefuseABlockedCorridor) {
  const FloorPlan plan = SyntheticOffice(6);
  const RoutePlanner planner(plan);
  const Eigen::Vector2d from(2.5, 4), to(27.5, 4);  // first and last north rooms
  const Route free = planner.Plan(from, to);
  ASSERT_TRUE(free.ok()) << free.error;
  // A hazard of 0.2 m at the corridor's south wall leaves 1.8 m - 0.3 m: the route bends
  // round it, clear of it by the body radius and clear of the walls.
  const KeepOut hazard{{15.0, 0.2}, 0.2};
  const Route round = planner.Plan(from, to, {hazard});
  ASSERT_TRUE(round.ok()) << round.error;
  EXPECT_GE(ClosestTo(round.path, hazard),
            hazard.radius_m + planner.options().body_radius_m - 1e-9);
  EXPECT_GE(PathClearance(round.path, plan.segments), planner.options().body_radius_m - 1e-9);
  EXPECT_EQ(round.path.back(), to);
  // Across the whole corridor: refused, and said so.
  const Route shut = planner.Plan(from, to, {{{15.0, 1.0}, 1.0}});
  EXPECT_FALSE(shut.ok());
  EXPECT_NE(shut.error.find("blocked areas close every way"), std::string::npos) << shut.error;
  // A destination inside one: refused.
  const Route into = planner.Plan(from, to, {{to, 0.5}});
  EXPECT_NE(into.error.find("in a blocked area"), std::string::npos) << into.error;
  // A wearer standing in one walks out of it.
  const Route out = planner.Plan(from, to, {{from, 0.5}});
  EXPECT_TRUE(out.ok()) << out.error;
}

TEST(KeepOutTest, TheWayOutPassesOverABlockedExit) {
  // Exits at both ends of the corridor (its west wall x = 0 and east wall x = 30).
  std::vector<PlanLine> lines;
  for (const Segment& s : SyntheticOffice(6).segments) lines.push_back({s, LineKind::kWall});
  lines.push_back({{{0, 0.5}, {0, 1.5}}, LineKind::kExit});
  lines.push_back({{{30, 0.5}, {30, 1.5}}, LineKind::kExit});
  const FloorPlan plan = MakeFloorPlan("two-exits", lines, {}).plan;
  ASSERT_EQ(plan.openings.size(), 2u);
  const RoutePlanner planner(plan);
  const Eigen::Vector2d from(7.5, 1.0);
  const Route near = planner.WayOut(from);
  ASSERT_TRUE(near.ok()) << near.error;
  EXPECT_LT(near.path.back().x(), 1.0) << "the west exit is nearer";
  const Route far = planner.WayOut(from, {{{0, 1.0}, 1.0}});
  ASSERT_TRUE(far.ok()) << far.error;
  EXPECT_GT(far.path.back().x(), 29.0) << "the west exit is blocked";
  EXPECT_GE(PathClearance(far.path, plan.segments), planner.options().body_radius_m - 1e-9);
  EXPECT_FALSE(planner.WayOut(from, {{{0, 1.0}, 1.0}, {{30, 1.0}, 1.0}}).ok());
}

TEST(KeepOutTest, ThroughFollowsTheWayWalkedAndPassesOverWaypointsItCannotReach) {
  // A ring corridor 4 m wide round a block: two ways from the east side to the south-west
  // corner, the short one south, the long one north (the way the wearer came).
  std::vector<Segment> walls = {{{0, 0}, {20, 0}},   {{20, 0}, {20, 20}}, {{20, 20}, {0, 20}},
                                {{0, 20}, {0, 0}},   {{4, 4}, {16, 4}},   {{16, 4}, {16, 16}},
                                {{16, 16}, {4, 16}}, {{4, 16}, {4, 4}}};
  const FloorPlan plan = MakeFloorPlan("ring", walls).plan;
  const RoutePlanner planner(plan);
  const Eigen::Vector2d from(18, 10), to(2, 2);
  const std::vector<Eigen::Vector2d> came = {{18, 18}, {10, 18}, {10, 10}, {2, 18}, {2, 10}};
  const Route back = planner.Through(from, came, to);
  ASSERT_TRUE(back.ok()) << back.error;
  EXPECT_EQ(back.path.front(), from);
  EXPECT_EQ(back.path.back(), to);
  EXPECT_GE(PathClearance(back.path, plan.segments), planner.options().body_radius_m - 1e-9);
  double north = 0;
  for (const Eigen::Vector2d& p : back.path) north = std::max(north, p.y());
  EXPECT_GT(north, 16.0) << "the way it came, round the north";
  EXPECT_GT(back.length_m, planner.Plan(from, to).length_m + 10.0);
  // A hazard on the north side: the way back goes round it where it can...
  const KeepOut hazard{{10, 19}, 0.5};
  const Route round = planner.Through(from, came, to, {hazard});
  ASSERT_TRUE(round.ok()) << round.error;
  EXPECT_GE(ClosestTo(round.path, hazard),
            hazard.radius_m + planner.options().body_radius_m - 1e-9);
  // ...and takes the other way when the north side is shut.
  const KeepOut shut{{10, 18}, 2.0};
  const Route other = planner.Through(from, came, to, {shut});
  ASSERT_TRUE(other.ok()) << other.error;
  EXPECT_GE(ClosestTo(other.path, shut), shut.radius_m + planner.options().body_radius_m - 1e-9);
  EXPECT_GE(PathClearance(other.path, plan.segments), planner.options().body_radius_m - 1e-9);
}

}  // namespace
}  // namespace floorpose
