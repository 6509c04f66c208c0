// The alignment filter: perturbations about the wearer, covariance moved with the wearer,
// degenerate directions left to the prior, and the gate.
#include "core/alignment_filter.h"

#include <gtest/gtest.h>

#include "core/random.h"
#include "tests/test_util.h"

namespace floorpose {
namespace {

using testing::Deg;
using testing::IsNearlySe2;

TEST(AlignmentFilterTest, DifferenceAndPerturbAreInverse) {
  SplitMix64 rng(61);
  for (int i = 0; i < 200; ++i) {
    const Se2 from{rng.Uniform(-M_PI, M_PI), {rng.Uniform(-30, 30), rng.Uniform(-30, 30)}};
    const Se2 to{rng.Uniform(-M_PI, M_PI), {rng.Uniform(-30, 30), rng.Uniform(-30, 30)}};
    const Eigen::Vector2d pivot(rng.Uniform(-20, 20), rng.Uniform(-20, 20));
    const Eigen::Vector3d d = Difference(to, from, pivot);
    EXPECT_THAT(Perturb(from, d, pivot), IsNearlySe2(to, 1e-9, 1e-12));
  }
  // A rotation about the pivot leaves the pivot where it was: u = 0.
  const Eigen::Vector2d pivot(5, -2);
  const Se2 from{0.3, {1, 2}};
  const Se2 turned = Perturb(from, {0.1, 0, 0}, pivot);
  EXPECT_NEAR((turned * (from.Inverse() * pivot) - pivot).norm(), 0.0, 1e-12);
}

TEST(AlignmentFilterTest, CorridorAxisKeepsThePrior) {
  // Two long parallel walls along x: the points say nothing about x.
  auto plan = MakeFloorPlan("corridor", {{{-50, 0}, {50, 0}}, {{-50, 2}, {50, 2}}});
  ASSERT_TRUE(plan.ok());
  const ClosestWallIndex index(plan.plan);
  std::vector<Eigen::Vector2d> cloud;
  for (double x = -5; x <= 5; x += 0.05) {
    cloud.emplace_back(x, 0.0);
    cloud.emplace_back(x, 2.0);
  }
  AlignmentFilter filter;
  const Eigen::Vector2d wearer(0, 1);
  filter.Reset(Se2{}, Eigen::Vector3d(1e-3, 0.25, 0.25).asDiagonal(), wearer);
  size_t inliers = 0;
  const Eigen::Matrix3d H = FitInformation(cloud, index, Se2{}, wearer, 0.2, &inliers);
  EXPECT_EQ(inliers, cloud.size());
  EXPECT_NEAR(H(1, 1), 0.0, 1e-9);  // no information along the axis
  const Eigen::Matrix3d R = filter.MeasurementCovariance(H, inliers);
  // A registration that slid 0.4 m along the axis (free) and 0.1 m across it.
  const AlignmentFilter::Update u = filter.Fuse(Se2{0.0, {0.4, 0.1}}, R);
  ASSERT_FALSE(u.gated);
  EXPECT_LT(std::abs(filter.T().t.x()), 0.01);          // the prior holds along the axis
  EXPECT_NEAR(filter.T().t.y(), 0.1, 0.005);            // the walls decide across it
  EXPECT_GT(filter.P()(1, 1), 100 * filter.P()(2, 2));  // and it stays uncertain along it
}

TEST(AlignmentFilterTest, UncertaintyGrowsWithWalkAndMovesWithTheWearer) {
  AlignmentFilter filter;
  filter.Reset(Se2{}, Eigen::Matrix3d::Zero(), {0, 0});
  filter.Predict({0, 0}, 100.0);
  const AlignmentFilterOptions& o = filter.options();
  EXPECT_NEAR(filter.P()(0, 0), o.heading_var_per_m * 100, 1e-12);
  EXPECT_NEAR(filter.position_sigma_m(), std::sqrt(o.position_var_per_m * 100), 1e-9);
  // Only heading uncertainty, then 10 m away: it becomes 10 m of lever arm.
  filter.Reset(Se2{}, Eigen::Vector3d(Deg(1) * Deg(1), 0, 0).asDiagonal(), {0, 0});
  filter.Predict({10, 0}, 0.0);
  EXPECT_NEAR(filter.position_sigma_m(), 10 * Deg(1), 1e-9);
}

TEST(AlignmentFilterTest, HeadingDriftsWithTheNetTurnNotWithScanning) {
  AlignmentFilter filter;
  const double s = filter.options().yaw_scale_sigma;
  ASSERT_GT(s, 0);
  filter.Reset(Se2{}, Eigen::Matrix3d::Zero(), {0, 0});
  // A head scanning 60 degrees left and right a hundred times, standing still: only the
  // widest swing counts.
  for (int i = 0; i < 100; ++i) {
    filter.Predict({0, 0}, 0.0, Deg(60));
    filter.Predict({0, 0}, 0.0, -Deg(60));
  }
  EXPECT_NEAR(filter.P()(0, 0), s * s * Deg(60) * Deg(60), 1e-12);
  // Five laps of a hall one way: (s x 5 turns)^2.
  filter.Reset(Se2{}, Eigen::Matrix3d::Zero(), {0, 0});
  for (int i = 0; i < 5 * 36; ++i) filter.Predict({0, 0}, 0.0, Deg(10));
  EXPECT_NEAR(std::sqrt(filter.P()(0, 0)), s * 5 * 2 * M_PI, 1e-9);
  // A fused registration starts the count again.
  const double before = filter.P()(0, 0);
  ASSERT_FALSE(filter.Fuse(Se2{}, Eigen::Vector3d(Deg(1) * Deg(1), 0.01, 0.01).asDiagonal()).gated);
  const double after = filter.P()(0, 0);
  EXPECT_LT(after, before);
  filter.Predict({0, 0}, 0.0, Deg(90));
  EXPECT_NEAR(filter.P()(0, 0), after + s * s * Deg(90) * Deg(90), 1e-12);
}

TEST(AlignmentFilterTest, GatesAResultFarBeyondTheUncertainty) {
  AlignmentFilter filter;
  filter.Reset(Se2{}, Eigen::Vector3d(Deg(1) * Deg(1), 0.01, 0.01).asDiagonal(), {0, 0});
  const Eigen::Matrix3d R = Eigen::Vector3d(Deg(0.5) * Deg(0.5), 0.0025, 0.0025).asDiagonal();
  const AlignmentFilter::Update far = filter.Fuse(Se2{0.0, {3.0, 0}}, R);
  EXPECT_TRUE(far.gated);
  EXPECT_GT(far.mahalanobis2, filter.options().gate_chi2);
  EXPECT_THAT(filter.T(), IsNearlySe2(Se2{}, 0, 0));  // untouched
  const AlignmentFilter::Update near = filter.Fuse(Se2{0.0, {0.1, 0}}, R);
  EXPECT_FALSE(near.gated);
  // Prior 0.1 m, measurement 0.05 m: the estimate goes 4/5 of the way.
  EXPECT_NEAR(filter.T().t.x(), 0.08, 1e-9);
}

// A device whose heading drifts 2 degrees a metre (wheel odometry), against the prior of
// 0.3 degrees per square root metre: with the prior alone nearly every correct result is
// beyond the gate; learning the drift from the innovations lets them in. A device that
// drifts as the prior says leaves the scale near 1.
int GatedResults(int drift_window, double drift_deg_per_m, double* scale) {
  AlignmentFilterOptions o;
  o.drift_window = drift_window;
  AlignmentFilter filter(o);
  filter.Reset(Se2::Identity(), Eigen::Vector3d(1e-4, 0.01, 0.01).asDiagonal(), {0, 0});
  SplitMix64 rng(5);
  const Eigen::Matrix3d R = Eigen::Vector3d(Deg(0.2) * Deg(0.2), 0.01, 0.01).asDiagonal();
  Se2 truth = Se2::Identity();
  int gated = 0;
  for (int metre = 1; metre <= 60; ++metre) {
    const Eigen::Vector2d wearer(metre, 0.0);
    const double turn = drift_deg_per_m > 0 ? Deg(drift_deg_per_m) : Deg(0.3) * rng.Gaussian();
    truth = Perturb(truth, {turn, 0, 0}, wearer);
    filter.Predict(wearer, 1.0);
    const Se2 measured = Perturb(
        truth, {Deg(0.2) * rng.Gaussian(), 0.1 * rng.Gaussian(), 0.1 * rng.Gaussian()}, wearer);
    gated += filter.Fuse(measured, R).gated;
  }
  *scale = filter.drift_scale();
  return gated;
}

TEST(AlignmentFilterTest, LearnsADriftFasterThanThePrior) {
  double prior_scale = 0, learnt_scale = 0, steady_scale = 0;
  const int prior_gated = GatedResults(0, 2.0, &prior_scale);
  const int learnt_gated = GatedResults(9, 2.0, &learnt_scale);
  EXPECT_EQ(prior_scale, 1.0);
  EXPECT_GT(prior_gated, 30);
  EXPECT_GT(learnt_scale, 10.0);
  EXPECT_LT(learnt_gated, 10);
  GatedResults(9, 0.0, &steady_scale);
  EXPECT_LT(steady_scale, 3.0);
}

}  // namespace
}  // namespace floorpose
