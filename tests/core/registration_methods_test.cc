// Issue 3's acceptance on synthetic plans, for every method: seeded scans of a room, an
// apartment and an office floor (wall points in the slam frame, a known T_slam_plan),
// started from the truth with an error about the walker's area. Register runs with the
// correlative search over the error's range in front of the method (RunCases in
// tests/registration_scenarios.h), as after a wall pick.
//   - ICP and IK, errors up to 10 degrees and 2 m: within 2 cm and 0.2 degrees on clean
//     wall points; within 10 cm and 1 degree with 4 cm noise and 30% clutter.
//   - Hough, errors up to 30 degrees: the rotation within 1 degree.
//   - A corridor (all walls parallel), without the search: the axis is reported
//     degenerate and the solution does not move along it, where plain IK (no solution
//     remapping) ran off in the thesis (figure 7.9); the log says how far it moves here.
// The same checks on the real floor plans are in tests/platform/registration_real_plans_test.cc.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "core/closest_wall_index.h"
#include "core/random.h"
#include "core/registration.h"
#include "tests/registration_scenarios.h"
#include "tests/test_util.h"

namespace floorpose {
namespace {

using testing::Box;
using testing::Condition;
using testing::Deg;

FloorPlan Plan(const std::string& id, std::vector<Segment> walls) {
  auto parse = MakeFloorPlan(id, std::move(walls));
  EXPECT_TRUE(parse.ok()) << parse.error;
  return parse.plan;
}

// A 12 x 9 m apartment: four rooms joined by 1 m doorways.
FloorPlan Apartment() {
  return Plan("apartment", {{{0, 0}, {12, 0}},
                            {{12, 0}, {12, 9}},
                            {{12, 9}, {0, 9}},
                            {{0, 9}, {0, 0}},
                            {{5, 0}, {5, 3}},  // living room | bedrooms, door at y 3-4
                            {{5, 4}, {5, 9}},
                            {{0, 5}, {2, 5}},  // kitchen | living room, door at x 2-3
                            {{3, 5}, {5, 5}},
                            {{5, 4}, {8, 4}},  // bedroom | hall, door at x 8-9
                            {{9, 4}, {12, 4}},
                            {{9, 4}, {9, 6}},  // bedroom | bath, door at y 6-7
                            {{9, 7}, {9, 9}},
                            {{0, 7}, {1.5, 7}}});  // a kitchen counter end
}

// A 40 x 14 m office floor: a 2 m corridor (y 6 to 8) with offices of uneven widths on
// both sides, each with a 1 m door onto the corridor. Registered in 15 m windows.
FloorPlan OfficeFloor() {
  std::vector<Segment> walls = {
      {{0, 0}, {40, 0}}, {{40, 0}, {40, 14}}, {{40, 14}, {0, 14}}, {{0, 14}, {0, 0}}};
  auto side = [&](const std::vector<double>& xs, double y_wall, double y_far) {
    double door_from = 0;
    for (size_t i = 0; i <= xs.size(); ++i) {
      const double x0 = i == 0 ? 0 : xs[i - 1], x1 = i == xs.size() ? 40 : xs[i];
      if (i < xs.size()) walls.push_back({{x1, y_wall}, {x1, y_far}});  // partition
      const double door = 0.5 * (x0 + x1);                              // door at the middle
      walls.push_back({{door_from, y_wall}, {door - 0.5, y_wall}});
      door_from = door + 0.5;
    }
    walls.push_back({{door_from, y_wall}, {40, y_wall}});
  };
  side({3.5, 7.5, 10.5, 15, 19, 22.5, 27, 31, 34.5}, 6, 0);
  side({4.5, 9, 13, 18.5, 23, 26.5, 31.5, 36}, 8, 14);
  return Plan("office-floor", walls);
}

struct Scenario {
  std::string name;
  FloorPlan plan;
  std::vector<Box> windows;  // one scan per window and case
  int cases = 0;             // per window
};

// Small plans are seen whole; the office floor in 15 m windows along the corridor.
std::vector<Scenario> Scenarios() {
  std::vector<Scenario> out;
  for (FloorPlan plan : {testing::AsymmetricRoom(), Apartment()}) {
    const Box whole{plan.min - Eigen::Vector2d::Constant(0.5),
                    plan.max + Eigen::Vector2d::Constant(0.5)};
    out.push_back({plan.id, plan, {whole}, 12});
  }
  FloorPlan office = OfficeFloor();
  std::vector<Box> windows;
  for (double x : {7.5, 13.0, 20.0, 26.0, 32.5}) windows.push_back(Box::Around({x, 7.0}, 15.0));
  out.push_back({office.id, office, windows, 3});
  return out;
}

uint64_t SeedOf(const std::string& s) {
  uint64_t h = 1469598103934665603ULL;  // FNV-1a
  for (char c : s) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
  return h;
}

// Every case of every scenario must meet the condition; prints one summary line per
// scenario (the log the issue asks for) and lists the cases that miss.
void ExpectRequirement(RegistrationMethod method, const Condition& condition) {
  for (const Scenario& s : Scenarios()) {
    const ClosestWallIndex index(s.plan);
    std::vector<std::string> failures;
    // The same seed for every method: they all see the same scans and initial guesses.
    const testing::Tally tally =
        testing::RunCases(s.plan, index, s.windows, s.cases, method, condition,
                          SeedOf(s.name + condition.name), &failures);
    std::printf("[ summary  ] %-12s %-5s %-14s %s\n", s.name.c_str(), ToString(method),
                condition.name.c_str(), tally.Summary().c_str());
    EXPECT_EQ(tally.failed, 0) << s.name << ", " << condition.name << ": " << tally.Summary()
                               << testing::FirstLines(failures);
  }
}

// ICP and IK: the translation and rotation requirements.
class RegistrationRequirementTest : public ::testing::TestWithParam<RegistrationMethod> {};

TEST_P(RegistrationRequirementTest, CleanPointsWithin2cmAnd02Degrees) {
  ExpectRequirement(GetParam(), testing::Clean());
}

TEST_P(RegistrationRequirementTest, NoisyClutteredPointsWithin10cmAnd1Degree) {
  ExpectRequirement(GetParam(), testing::NoisyCluttered());
}

INSTANTIATE_TEST_SUITE_P(Methods, RegistrationRequirementTest,
                         ::testing::Values(RegistrationMethod::kIcp, RegistrationMethod::kIk),
                         [](const ::testing::TestParamInfo<RegistrationMethod>& m) {
                           return std::string(ToString(m.param));
                         });

// Hough: the rotation requirement, from up to 30 degrees, clean and noisy.
TEST(HoughRequirementTest, RotationWithin1DegreeFrom30Degrees) {
  ExpectRequirement(RegistrationMethod::kHough, testing::HoughRotation(testing::Clean()));
  ExpectRequirement(RegistrationMethod::kHough, testing::HoughRotation(testing::NoisyCluttered()));
}

// Corridors, all walls parallel: two 60 m walls 2 m apart, seen over 15 m of their
// middle, started 1 m off along the axis (nothing in the data says where along it the
// walker is), clean and with 4 cm noise and 30% clutter. The axis (plan x) must be
// reported degenerate, in (theta * r, x, y), and the solution must move less than 5 cm
// along it; rotation and the offset across are still found. Without solution remapping
// (degeneracy_ratio 0) the thesis' IK ran off along a corridor (figure 7.9): a log line
// says how far the plain solve moved here.
//   two walls: each wall one segment.
//   pieces:    each wall drawn in 3 m pieces with 2 cm joints, as digitised plans often
//              are; IK's point-to-point rows at segment ends (Pottmann et al. 2004) see
//              the joints, a weak and spurious pull along the axis.
FloorPlan Corridor(bool pieces) {
  if (!pieces) return Plan("corridor", {{{0, 0}, {60, 0}}, {{0, 2}, {60, 2}}});
  std::vector<Segment> walls;
  for (double x = 0; x < 60; x += 3) {
    walls.push_back({{x, 0}, {x + 2.98, 0}});
    walls.push_back({{x + 1.5, 2}, {x + 4.48, 2}});  // joints staggered across
  }
  return Plan("corridor-pieces", walls);
}

struct CorridorCase {
  RegistrationMethod method;
  bool pieces;
};

class CorridorTest : public ::testing::TestWithParam<CorridorCase> {};

TEST_P(CorridorTest, AxisIsReportedDegenerateAndNotMovedAlong) {
  const FloorPlan corridor = Corridor(GetParam().pieces);
  const ClosestWallIndex index(corridor);
  const Box window{{22.5, -0.5}, {37.5, 2.5}};
  RegistrationOptions remapped, plain;
  remapped.method = plain.method = GetParam().method;
  plain.icp.degeneracy_ratio = 0;
  for (const Condition& condition : {testing::Clean(), testing::NoisyCluttered()}) {
    SplitMix64 rng(SeedOf(corridor.id + condition.name));
    double remapped_worst_m = 0, plain_worst_m = 0;
    for (int k = 0; k < 8; ++k) {
      SCOPED_TRACE(condition.name + " case " + std::to_string(k));
      const Se2 T_slam_plan = testing::RandomSe2(rng, M_PI, 30.0);
      const Se2 truth = T_slam_plan.Inverse();
      const testing::Scan scan =
          testing::MakeScan(corridor, window, T_slam_plan, condition.scan, rng);
      const double along = rng.Uniform() < 0.5 ? -1.0 : 1.0;
      const Se2 initial = testing::PerturbAbout(
          truth, window.Centre(), rng.Uniform(-Deg(5), Deg(5)), {along, rng.Uniform(-0.3, 0.3)});
      // The walker's area in the slam frame, and where each transform puts it.
      const Eigen::Vector2d centre_slam = T_slam_plan * window.Centre();
      const Eigen::Vector2d start = initial * centre_slam;

      const RegistrationResult r = Register(scan.points, scan.normals, index, initial, remapped);
      EXPECT_FALSE(r.degenerate_directions.empty())
          << "no degenerate direction; eigenvalues " << r.eigenvalues.transpose();
      if (!r.degenerate_directions.empty()) {
        EXPECT_GT(std::abs(r.degenerate_directions[0](1)), 0.9)  // mostly x: the axis
            << r.degenerate_directions[0].transpose();
      }
      const Eigen::Vector2d end = r.T_plan_slam * centre_slam;
      EXPECT_LT(std::abs(end.x() - start.x()), 0.05) << "moved along the corridor";
      EXPECT_LT(std::abs(end.y() - window.Centre().y()), condition.tolerance_m) << "across";
      EXPECT_LT(std::abs(WrapAngle(r.T_plan_slam.theta - truth.theta)), condition.tolerance_rad);
      remapped_worst_m = std::max(remapped_worst_m, std::abs(end.x() - start.x()));

      const RegistrationResult p = Register(scan.points, scan.normals, index, initial, plain);
      plain_worst_m = std::max(plain_worst_m, std::abs((p.T_plan_slam * centre_slam - start).x()));
    }
    std::printf(
        "[ summary  ] %-15s %-3s %-5s moved along the axis up to %.3f m; without solution "
        "remapping up to %.3f m\n",
        corridor.id.c_str(), ToString(GetParam().method), condition.name.c_str(), remapped_worst_m,
        plain_worst_m);
  }
}

INSTANTIATE_TEST_SUITE_P(Corridors, CorridorTest,
                         ::testing::Values(CorridorCase{RegistrationMethod::kIcp, false},
                                           CorridorCase{RegistrationMethod::kIk, false},
                                           CorridorCase{RegistrationMethod::kIcp, true},
                                           CorridorCase{RegistrationMethod::kIk, true}),
                         [](const ::testing::TestParamInfo<CorridorCase>& c) {
                           return std::string(ToString(c.param.method)) +
                                  (c.param.pieces ? "_pieces" : "_two_walls");
                         });

}  // namespace
}  // namespace floorpose
