// Registration on a synthetic room with a known answer: wall points sampled on the plan,
// moved into the slam frame by a known T_slam_plan. Point-to-line ICP (thesis Algorithm
// 4.2) in detail; instantaneous kinematics (Algorithms 4.3-4.5) and Hough (4.6, 4.7)
// through the common entry point.
#include "core/registration.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <limits>

#include "core/random.h"
#include "core/thin_cloud.h"
#include "tests/test_util.h"

namespace floorpose {
namespace {

using testing::Deg;
using testing::IsNearlySe2;

// Wall points with their wall normals in the slam frame: points every 2 cm on the plan
// walls, mapped by T_slam_plan, with Gaussian noise of noise_m per axis. Walls are
// two-sided, so each wall's normal gets a random sign.
struct Cloud {
  std::vector<Eigen::Vector2d> points, normals;
};

Cloud SlamCloudWithNormals(const FloorPlan& plan, const Se2& T_slam_plan, double noise_m,
                           uint64_t seed) {
  SplitMix64 rng(seed);
  Cloud out;
  for (const Segment& s : plan.segments) {
    const Eigen::Vector2d n = T_slam_plan.R() * s.Normal() * (rng.Uniform() < 0.5 ? -1.0 : 1.0);
    const FloorPlan one{"", {s}, {}, {}, {}, {}, {}};
    for (const Eigen::Vector2d& p : testing::SampleWalls(one, 0.02)) {
      const Eigen::Vector2d noise(rng.Gaussian(), rng.Gaussian());
      out.points.push_back(T_slam_plan * p + noise_m * noise);
      out.normals.push_back(n);
    }
  }
  return out;
}

std::vector<Eigen::Vector2d> SlamCloud(const FloorPlan& plan, const Se2& T_slam_plan,
                                       double noise_m, uint64_t seed) {
  return SlamCloudWithNormals(plan, T_slam_plan, noise_m, seed).points;
}

class IcpTest : public ::testing::Test {
 protected:
  IcpTest() : plan_(testing::AsymmetricRoom()), index_(plan_) {}
  FloorPlan plan_;
  ClosestWallIndex index_;
  IcpOptions options_;
};

TEST_F(IcpTest, RecoversKnownTransformFromIdentity) {
  // The example of the brief: 5 degrees and 0.8 m between slam and plan.
  const Se2 T_slam_plan{Deg(5), {0.8, 0.0}};
  const Se2 truth = T_slam_plan.Inverse();
  const auto cloud = SlamCloud(plan_, T_slam_plan, 0.0, 1);
  const RegistrationResult r = RegisterIcp(cloud, index_, Se2::Identity(), options_);
  EXPECT_TRUE(r.converged) << r.reason;
  EXPECT_THAT(r.T_plan_slam, IsNearlySe2(truth, 0.02, Deg(0.2)));
}

TEST_F(IcpTest, RecoversSeededRandomTransformsOnCleanPoints) {
  SplitMix64 rng(31);
  for (int i = 0; i < 10; ++i) {
    SCOPED_TRACE("case " + std::to_string(i));
    const Se2 T_slam_plan = testing::RandomSe2(rng, Deg(6), 0.6);
    const Se2 truth = T_slam_plan.Inverse();
    // The initial guess is the truth with an error, as a wall pick would give.
    const Se2 error = testing::RandomSe2(rng, Deg(4), 0.4);
    const auto cloud = SlamCloud(plan_, T_slam_plan, 0.0, 100 + i);
    const RegistrationResult r = RegisterIcp(cloud, index_, error * truth, options_);
    EXPECT_TRUE(r.converged) << r.reason;
    EXPECT_THAT(r.T_plan_slam, IsNearlySe2(truth, 0.02, Deg(0.2)));
    EXPECT_LT(r.inlier_rmse, 0.005);
    // On exact data Gauss-Newton needs a few steps per level (5 to 7 in all here); many
    // more would mean a wrong Jacobian (eq. 4.4), even if it crawls to the answer.
    EXPECT_LE(r.iterations, 15u);
  }
}

TEST_F(IcpTest, ALargeCloudPolishesOnceAtTheFinestLevel) {
  // 64 copies of the room's walls at 2 mm noise: the coarsest level (about 500 points)
  // already knows the fit within the convergence thresholds, so the levels between are
  // skipped and the finest level polishes once. Walking every level would take at least
  // one pass each: 12 in all here.
  const Se2 T_slam_plan{Deg(3), {0.3, -0.2}};
  const Se2 truth = T_slam_plan.Inverse();
  std::vector<Eigen::Vector2d> cloud;
  for (uint64_t seed = 0; seed < 64; ++seed) {
    const auto copy = SlamCloud(plan_, T_slam_plan, 0.002, 400 + seed);
    cloud.insert(cloud.end(), copy.begin(), copy.end());
  }
  ASSERT_GT(cloud.size(), 100000u);
  const RegistrationResult r = RegisterIcp(cloud, index_, Se2::Identity(), options_);
  ASSERT_TRUE(r.converged) << r.reason;
  EXPECT_THAT(r.T_plan_slam, IsNearlySe2(truth, 1e-4, 1e-5));
  EXPECT_LE(r.iterations, 8u) << "levels walked that the fit's noise made unnecessary";
}

TEST_F(IcpTest, NoisyPointsStayWithinFiveCentimetres) {
  SplitMix64 rng(32);
  for (int i = 0; i < 6; ++i) {
    SCOPED_TRACE("case " + std::to_string(i));
    const double noise = i % 2 == 0 ? 0.01 : 0.02;
    const Se2 T_slam_plan = testing::RandomSe2(rng, Deg(5), 0.8);
    const Se2 truth = T_slam_plan.Inverse();
    const auto cloud = SlamCloud(plan_, T_slam_plan, noise, 200 + i);
    const RegistrationResult r = RegisterIcp(cloud, index_, Se2::Identity(), options_);
    EXPECT_THAT(r.T_plan_slam, IsNearlySe2(truth, 0.05, Deg(0.5)));
    // The residual is the noise across the walls, not the alignment error.
    EXPECT_NEAR(r.inlier_rmse, noise, 0.5 * noise);
  }
}

TEST_F(IcpTest, ClutterIsRejected) {
  // A third of the points are clutter (furniture, people) spread over the room. Picky
  // rejection and the Cauchy kernel keep them from pulling the fit.
  SplitMix64 rng(34);
  for (int i = 0; i < 6; ++i) {
    SCOPED_TRACE("case " + std::to_string(i));
    const Se2 T_slam_plan = testing::RandomSe2(rng, Deg(5), 0.8);
    const Se2 truth = T_slam_plan.Inverse();
    auto cloud = SlamCloud(plan_, T_slam_plan, 0.01, 400 + i);
    const size_t walls = cloud.size();
    for (size_t k = 0; k < walls / 2; ++k)
      cloud.push_back(T_slam_plan * testing::RandomVector2(rng, {0.5, 0.5}, {9.5, 6.5}));
    const RegistrationResult r = RegisterIcp(cloud, index_, Se2::Identity(), options_);
    EXPECT_TRUE(r.converged) << r.reason;
    EXPECT_THAT(r.T_plan_slam, IsNearlySe2(truth, 0.05, Deg(0.5)));
  }
}

TEST_F(IcpTest, TheOrderOfThePointsDoesNotMatter) {
  // The coarse levels take every 2^h-th point, so a shuffled cloud starts from other
  // subsets; the finest level, every point, lands it where the ordered cloud lands.
  const Se2 T_slam_plan{Deg(4), {0.5, -0.3}};
  const Se2 truth = T_slam_plan.Inverse();
  auto cloud = SlamCloud(plan_, T_slam_plan, 0.01, 4);
  const RegistrationResult ordered = RegisterIcp(cloud, index_, Se2::Identity(), options_);
  SplitMix64 rng(5);
  for (size_t i = cloud.size() - 1; i > 0; --i)
    std::swap(cloud[i], cloud[static_cast<size_t>(rng.Uniform() * static_cast<double>(i + 1))]);
  const RegistrationResult shuffled = RegisterIcp(cloud, index_, Se2::Identity(), options_);
  ASSERT_TRUE(ordered.converged) << ordered.reason;
  ASSERT_TRUE(shuffled.converged) << shuffled.reason;
  EXPECT_THAT(ordered.T_plan_slam, IsNearlySe2(truth, 0.005, Deg(0.05)));
  EXPECT_THAT(shuffled.T_plan_slam, IsNearlySe2(ordered.T_plan_slam, 0.001, Deg(0.01)));
  EXPECT_EQ(shuffled.points, ordered.points);
  EXPECT_NEAR(shuffled.inliers, ordered.inliers, 0.01 * ordered.points);
}

TEST_F(IcpTest, ReportFieldsAreFilled) {
  const Se2 T_slam_plan{Deg(3), {0.3, -0.2}};
  const auto cloud = SlamCloud(plan_, T_slam_plan, 0.005, 3);
  const RegistrationResult r = RegisterIcp(cloud, index_, Se2::Identity(), options_);
  EXPECT_EQ(r.method, "icp");
  EXPECT_TRUE(r.converged) << r.reason;
  EXPECT_TRUE(r.reason.empty()) << r.reason;
  EXPECT_GT(r.iterations, 0u);
  EXPECT_LE(r.iterations, options_.max_iterations * 2);  // 50/4 + 50/2 + 50 at most
  EXPECT_EQ(r.points, cloud.size());
  EXPECT_LE(r.inliers, r.matched);
  EXPECT_LE(r.matched, r.points);
  EXPECT_GT(r.inliers, 0.98 * static_cast<double>(r.points));
  EXPECT_GT(r.rmse, 0.0);
  EXPECT_LE(r.inlier_rmse, r.rmse + 1e-12);
  // The normal matrix is symmetric and, in a closed room, positive definite.
  EXPECT_TRUE(r.normal_matrix.isApprox(r.normal_matrix.transpose()));
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(r.normal_matrix).eigenvalues()(0), 0.0);
  // The eigenvalues (of the radius-scaled matrix) ascend, are positive, and come with
  // an orthonormal basis; nothing is degenerate.
  EXPECT_LE(r.eigenvalues(0), r.eigenvalues(1));
  EXPECT_LE(r.eigenvalues(1), r.eigenvalues(2));
  EXPECT_GT(r.eigenvalues(0), 0.0);
  EXPECT_TRUE((r.eigenvectors.transpose() * r.eigenvectors).isIdentity(1e-9));
  EXPECT_TRUE(r.degenerate_directions.empty());
  EXPECT_EQ(r.time_ms, 0.0);  // the caller owns the clock
}

TEST_F(IcpTest, NormalMatrixIsTheSumOverThePairsInThetaXY) {
  // Plain least squares keeping every pair: the normal matrix is the sum of a a^T with
  // a = ((p - c) x n, n) over the pairs at the answer, c their centroid.
  // Corners left out: a point there is as near two walls, and a rounding picks one.
  const Se2 T_slam_plan{Deg(4), {0.2, -0.3}};
  std::vector<Eigen::Vector2d> cloud;
  for (const Eigen::Vector2d& q : SlamCloud(plan_, T_slam_plan, 0.005, 5)) {
    const Eigen::Vector2d p = T_slam_plan.Inverse() * q;
    const bool at_corner = std::any_of(
        plan_.segments.begin(), plan_.segments.end(),
        [&](const Segment& s) { return (p - s.a).norm() < 0.05 || (p - s.b).norm() < 0.05; });
    if (!at_corner) cloud.push_back(q);
  }
  IcpOptions plain = options_;
  plain.cauchy_scale_factor = 0;
  plain.reject_sigma = 1e9;
  // Converged far below a pair's switching: the last pass's pairs are the answer's.
  plain.converge_translation_m = 1e-9;
  plain.converge_rotation_rad = 1e-10;
  const RegistrationResult r = RegisterIcp(cloud, index_, Se2::Identity(), plain);
  ASSERT_TRUE(r.converged) << r.reason;
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> pairs;  // point, wall normal
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& q : cloud) {
    const Eigen::Vector2d p = r.T_plan_slam * q;
    const auto hit = index_.Query(p);
    if (!hit || hit->distance > plain.max_correspondence_m) continue;
    pairs.emplace_back(p, hit->normal);
    centroid += p;
  }
  ASSERT_GT(pairs.size(), 100u);
  centroid /= static_cast<double>(pairs.size());
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (const auto& [p, n] : pairs) {
    const Eigen::Vector2d d = p - centroid;
    const Eigen::Vector3d a(d.x() * n.y() - d.y() * n.x(), n.x(), n.y());
    H += a * a.transpose();
  }
  EXPECT_TRUE(r.normal_matrix.isApprox(H, 1e-3)) << r.normal_matrix << "\n\n" << H;
}

TEST_F(IcpTest, ThinningToVoxelsKeepsTheAnswer) {
  // A cloud sampled every 2 cm lands within a millimetre of where every point takes it.
  const Se2 T_slam_plan{Deg(-6), {0.4, 0.7}};
  const Se2 truth = T_slam_plan.Inverse();
  const auto cloud = SlamCloud(plan_, T_slam_plan, 0.01, 8);
  IcpOptions voxels = options_;
  voxels.voxel_m = 0.1;
  const RegistrationResult all = RegisterIcp(cloud, index_, Se2::Identity(), options_);
  const RegistrationResult thinned = RegisterIcp(cloud, index_, Se2::Identity(), voxels);
  ASSERT_TRUE(all.converged) << all.reason;
  ASSERT_TRUE(thinned.converged) << thinned.reason;
  // The counts are the cloud's: a voxel's point stands for all of the voxel's.
  EXPECT_EQ(thinned.points, cloud.size());
  EXPECT_NEAR(thinned.inliers, all.inliers, 0.01 * cloud.size());
  EXPECT_LT(VoxelMeans(cloud, voxels.voxel_m).points.size(), cloud.size() / 3);
  EXPECT_THAT(all.T_plan_slam, IsNearlySe2(truth, 0.003, Deg(0.05)));
  EXPECT_THAT(thinned.T_plan_slam, IsNearlySe2(all.T_plan_slam, 0.001, Deg(0.02)));
}

TEST(ThinCloudTest, KeepsTheFirstPointOfEachVoxelInOrder) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Eigen::Vector2d> cloud = {{0.01, 0.01}, {0.09, 0.05},  {nan, 0.0},
                                              {0.15, 0.02}, {-0.01, 0.02}, {0.02, 0.08},
                                              {0.11, 0.19}, {-0.05, -0.05}};
  const std::vector<Eigen::Vector2d> kept = ThinCloud(cloud, 0.1, 0);
  const std::vector<Eigen::Vector2d> expected = {
      {0.01, 0.01}, {0.15, 0.02}, {-0.01, 0.02}, {0.11, 0.19}, {-0.05, -0.05}};
  EXPECT_EQ(kept, expected);
  // The means of the same voxels, in the same order, with their counts.
  const VoxelCloud voxels = VoxelMeans(cloud, 0.1);
  ASSERT_EQ(voxels.points.size(), expected.size());
  EXPECT_TRUE(voxels.points[0].isApprox(Eigen::Vector2d(0.04, 0.14 / 3)));
  for (size_t i = 1; i < expected.size(); ++i) EXPECT_EQ(voxels.points[i], expected[i]);
  EXPECT_EQ(voxels.counts, (std::vector<uint32_t>{3, 1, 1, 1, 1}));
  // A limit takes every k-th of the voxels' points.
  EXPECT_EQ(ThinCloud(cloud, 0.1, 2), (std::vector<Eigen::Vector2d>{{0.01, 0.01}, {-0.01, 0.02}}));
}

TEST(ThinCloudTest, AFarPointThinsAsANearOne) {
  // A box too large for a voxel bitmap takes the hash set: the same voxels.
  std::vector<Eigen::Vector2d> cloud;
  for (double far : {0.0, 3e8, -1e300})
    for (int i = 0; i < 5; ++i) cloud.emplace_back(far + 0.01 * i, 0.35 + 0.01 * i);
  cloud.emplace_back(std::numeric_limits<double>::infinity(), 0.0);
  const std::vector<Eigen::Vector2d> kept = ThinCloud(cloud, 0.1, 0);
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_EQ(kept[0], cloud[0]);
  EXPECT_EQ(kept[1], cloud[5]);
  EXPECT_EQ(kept[2], cloud[10]);
  EXPECT_TRUE(ThinCloud({}, 0.1, 0).empty());
}

class RegistrationMethodTest : public ::testing::TestWithParam<RegistrationMethod> {
 protected:
  RegistrationMethodTest() : plan_(testing::AsymmetricRoom()), index_(plan_) {
    options_.method = GetParam();
  }
  FloorPlan plan_;
  ClosestWallIndex index_;
  RegistrationOptions options_;
};

TEST_P(RegistrationMethodTest, RecoversKnownTransformFromIdentity) {
  SplitMix64 rng(35);
  for (int i = 0; i < 6; ++i) {
    SCOPED_TRACE("case " + std::to_string(i));
    const Se2 T_slam_plan = testing::RandomSe2(rng, Deg(5), 0.8);
    const Se2 truth = T_slam_plan.Inverse();
    const Cloud cloud = SlamCloudWithNormals(plan_, T_slam_plan, 0.0, 500 + i);
    const RegistrationResult r =
        Register(cloud.points, cloud.normals, index_, Se2::Identity(), options_);
    EXPECT_EQ(r.method, ToString(GetParam()));
    EXPECT_TRUE(r.converged) << r.reason;
    EXPECT_THAT(r.T_plan_slam, IsNearlySe2(truth, 0.02, Deg(0.2)));
    EXPECT_EQ(r.points, cloud.points.size());
  }
}

TEST_P(RegistrationMethodTest, NoisyPointsStayWithinFiveCentimetres) {
  SplitMix64 rng(36);
  for (int i = 0; i < 4; ++i) {
    SCOPED_TRACE("case " + std::to_string(i));
    const Se2 T_slam_plan = testing::RandomSe2(rng, Deg(5), 0.8);
    const Cloud cloud = SlamCloudWithNormals(plan_, T_slam_plan, 0.02, 600 + i);
    const RegistrationResult r =
        Register(cloud.points, cloud.normals, index_, Se2::Identity(), options_);
    EXPECT_THAT(r.T_plan_slam, IsNearlySe2(T_slam_plan.Inverse(), 0.05, Deg(0.5)));
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, RegistrationMethodTest,
                         ::testing::Values(RegistrationMethod::kIcp, RegistrationMethod::kIk,
                                           RegistrationMethod::kHough),
                         [](const ::testing::TestParamInfo<RegistrationMethod>& m) {
                           return std::string(ToString(m.param));
                         });

TEST(RegistrationTest, MethodNamesRoundTrip) {
  for (RegistrationMethod m :
       {RegistrationMethod::kIcp, RegistrationMethod::kIk, RegistrationMethod::kHough}) {
    RegistrationMethod parsed = RegistrationMethod::kIcp;
    ASSERT_TRUE(ParseRegistrationMethod(ToString(m), &parsed)) << ToString(m);
    EXPECT_EQ(parsed, m);
  }
  RegistrationMethod unchanged = RegistrationMethod::kIk;
  EXPECT_FALSE(ParseRegistrationMethod("ICP", &unchanged));
  EXPECT_FALSE(ParseRegistrationMethod("", &unchanged));
  EXPECT_EQ(unchanged, RegistrationMethod::kIk);
}

TEST(RegistrationTest, WallBufferDropsPointsFarFromWalls) {
  // The thesis' 0.5 m buffer (section 6.4.3): under the initial transform, points more
  // than the buffer away from every wall do not enter the registration.
  const FloorPlan plan = testing::AsymmetricRoom();
  const ClosestWallIndex index(plan);
  const Se2 T_slam_plan{Deg(1), {0.05, 0.05}};
  Cloud cloud = SlamCloudWithNormals(plan, T_slam_plan, 0.0, 7);
  const size_t walls = cloud.points.size();
  SplitMix64 rng(37);
  for (int i = 0; i < 300; ++i) {  // clutter at least 1.5 m from every wall
    cloud.points.push_back(T_slam_plan * testing::RandomVector2(rng, {1.5, 1.5}, {2.5, 5.5}));
    cloud.normals.push_back({1, 0});
  }
  RegistrationOptions options;
  options.wall_buffer_m = 0.5;
  const RegistrationResult r =
      Register(cloud.points, cloud.normals, index, Se2::Identity(), options);
  EXPECT_EQ(r.points, walls);
  EXPECT_THAT(r.T_plan_slam, IsNearlySe2(T_slam_plan.Inverse(), 0.02, Deg(0.2)));
  options.wall_buffer_m = 0;
  EXPECT_EQ(Register(cloud.points, cloud.normals, index, Se2::Identity(), options).points,
            cloud.points.size());
}

TEST(RegistrationTest, HoughNeedsANormalPerPoint) {
  const FloorPlan plan = testing::AsymmetricRoom();
  const ClosestWallIndex index(plan);
  const Cloud cloud = SlamCloudWithNormals(plan, Se2{Deg(2), {0.1, 0.1}}, 0.0, 8);
  const Se2 initial{0.01, {0.02, 0.03}};
  const RegistrationResult r = RegisterHough(cloud.points, {}, index, initial, {}, {});
  EXPECT_FALSE(r.converged);
  EXPECT_THAT(r.reason, ::testing::HasSubstr("normal"));
  EXPECT_THAT(r.T_plan_slam, IsNearlySe2(initial, 0.0, 0.0));
}

TEST(IcpDegenerateTest, CorridorLeavesOneDirectionUnconstrained) {
  // Two parallel walls: sliding along x changes nothing. The smallest eigenvalue
  // vanishes, its direction is reported as degenerate (solution remapping), and the
  // constrained part is still found: the rotation and the offset across.
  auto parse = MakeFloorPlan("corridor", {{{0, 0}, {30, 0}}, {{0, 2}, {30, 2}}});
  ASSERT_TRUE(parse.ok());
  const ClosestWallIndex index(parse.plan);
  const Se2 T_slam_plan{Deg(2), {0.1, 0.3}};
  std::vector<Eigen::Vector2d> cloud;
  for (const auto& p : testing::SampleWalls(parse.plan, 0.05)) {
    if (p.x() > 10 && p.x() < 20) cloud.push_back(T_slam_plan * p);
  }
  const RegistrationResult r = RegisterIcp(cloud, index, Se2::Identity(), IcpOptions{});
  EXPECT_LT(r.eigenvalues(0), 1e-9 * r.eigenvalues(2)) << r.eigenvalues.transpose();
  EXPECT_GT(r.eigenvalues(1), 0.0);
  ASSERT_EQ(r.degenerate_directions.size(), 1u);
  EXPECT_NEAR(std::abs(r.degenerate_directions[0](1)), 1.0, 1e-6)  // (theta, x, y)
      << r.degenerate_directions[0].transpose();
  const Se2 truth = T_slam_plan.Inverse();
  EXPECT_NEAR(WrapAngle(r.T_plan_slam.theta - truth.theta), 0.0, Deg(0.2));
  for (const auto& p : cloud) {
    const Eigen::Vector2d q = r.T_plan_slam * p;
    EXPECT_NEAR(std::min(std::abs(q.y()), std::abs(q.y() - 2)), 0.0, 0.02);
  }
}

TEST(IcpDegenerateTest, TooFewPointsReturnsTheInitialGuess) {
  const ClosestWallIndex index(testing::AsymmetricRoom());
  const Se2 initial{0.1, {0.2, 0.3}};
  const RegistrationResult r = RegisterIcp({{0, 0}, {1, 0}}, index, initial, IcpOptions{});
  EXPECT_FALSE(r.converged);
  EXPECT_FALSE(r.reason.empty());
  EXPECT_THAT(r.T_plan_slam, IsNearlySe2(initial, 0.0, 0.0));
  EXPECT_EQ(r.points, 2u);

  const RegistrationResult empty = RegisterIcp({}, index, initial, IcpOptions{});
  EXPECT_FALSE(empty.converged);
  EXPECT_EQ(empty.points, 0u);
}

TEST(IcpDegenerateTest, PointsFarFromEveryWallDoNotConverge) {
  const FloorPlan plan = testing::AsymmetricRoom();
  const ClosestWallIndex index(plan);
  std::vector<Eigen::Vector2d> far;
  for (int i = 0; i < 100; ++i) far.push_back({100.0 + i, 100.0});
  const RegistrationResult r = RegisterIcp(far, index, Se2::Identity(), IcpOptions{});
  EXPECT_FALSE(r.converged);
  EXPECT_THAT(r.reason, ::testing::HasSubstr("correspondences"));
  EXPECT_EQ(r.matched, 0u);
  EXPECT_TRUE(r.T_plan_slam.t.allFinite());
}

TEST(EvaluateFitTest, ExactValuesOnOneWall) {
  // One long wall along x; points 0.1 m beside it, and as many points with no wall
  // within the correspondence distance.
  auto parse = MakeFloorPlan("wall", {{{0, 0}, {20, 0}}});
  ASSERT_TRUE(parse.ok());
  const ClosestWallIndex index(parse.plan);
  std::vector<Eigen::Vector2d> cloud;
  for (int i = 0; i < 50; ++i) cloud.push_back({1.0 + 0.3 * i, 0.1});
  RegistrationResult r;
  double mse = -1;
  EvaluateFit(cloud, index, Se2::Identity(), 1.5, 0.2, &r, &mse);
  EXPECT_EQ(r.points, 50u);
  EXPECT_EQ(r.matched, 50u);
  EXPECT_EQ(r.inliers, 50u);
  EXPECT_NEAR(r.rmse, 0.1, 1e-12);
  EXPECT_NEAR(r.inlier_rmse, 0.1, 1e-12);
  EXPECT_NEAR(mse, 0.01, 1e-12);

  // A tighter inlier threshold keeps the matches but drops the inliers.
  EvaluateFit(cloud, index, Se2::Identity(), 1.5, 0.05, &r, &mse);
  EXPECT_EQ(r.matched, 50u);
  EXPECT_EQ(r.inliers, 0u);
  EXPECT_EQ(r.inlier_rmse, 0.0);

  // The same points shifted onto the wall by the transform fit exactly.
  EvaluateFit(cloud, index, Se2{0, {0, -0.1}}, 1.5, 0.2, &r, &mse);
  EXPECT_NEAR(r.rmse, 0.0, 1e-12);
  EXPECT_NEAR(mse, 0.0, 1e-20);

  // Unmatched points count as the correspondence distance squared (section 6.4.3).
  for (int i = 0; i < 50; ++i) cloud.push_back({1.0 + 0.3 * i, 2.0});
  EvaluateFit(cloud, index, Se2::Identity(), 1.5, 0.2, &r, &mse);
  EXPECT_EQ(r.points, 100u);
  EXPECT_EQ(r.matched, 50u);
  EXPECT_NEAR(r.rmse, 0.1, 1e-12);
  EXPECT_NEAR(mse, (50 * 0.01 + 50 * 1.5 * 1.5) / 100, 1e-12);

  // No points: nothing matched, the worst score.
  EvaluateFit({}, index, Se2::Identity(), 1.5, 0.2, &r, &mse);
  EXPECT_EQ(r.points, 0u);
  EXPECT_EQ(r.rmse, 0.0);
  EXPECT_NEAR(mse, 2.25, 1e-12);
}

TEST(EvaluateFitTest, TruthScoresBetterThanAPerturbedTransform) {
  const FloorPlan plan = testing::AsymmetricRoom();
  const ClosestWallIndex index(plan);
  SplitMix64 rng(33);
  for (int i = 0; i < 10; ++i) {
    const Se2 T_slam_plan = testing::RandomSe2(rng, Deg(10), 1.0);
    const auto cloud = SlamCloud(plan, T_slam_plan, 0.01, 300 + i);
    const Se2 truth = T_slam_plan.Inverse();
    double at_truth = 0, off = 0;
    EvaluateFit(cloud, index, truth, 1.5, 0.2, nullptr, &at_truth);
    EvaluateFit(cloud, index, testing::RandomSe2(rng, Deg(3), 0.2) * truth, 1.5, 0.2, nullptr,
                &off);
    EXPECT_LT(at_truth, off);
    EXPECT_NEAR(at_truth, 0.01 * 0.01, 5e-5);  // the noise variance across the walls
  }
}

// The correlative search's ambiguity: one wall seen, and the plan has two parallel walls
// within the search window, so two places explain the points equally well; a room's
// corners leave one.
class OneWallOfTwoTest : public ::testing::Test {
 protected:
  static FloorPlan TwoWalls() {
    auto parse = MakeFloorPlan("two walls", {{{0, 0}, {20, 0}}, {{0, 2}, {20, 2}}});
    EXPECT_TRUE(parse.ok()) << parse.error;
    return parse.plan;
  }
  OneWallOfTwoTest() : index_(TwoWalls()) {
    // 7 m of the wall at y = 0, with 2 cm of noise, in a slam frame equal to the plan's.
    const FloorPlan seen{"", {{{5, 0}, {12, 0}}}, {}, {}, {}, {}, {}};
    points_ = testing::SampleWalls(seen, 0.05);
    SplitMix64 rng(3);
    for (Eigen::Vector2d& p : points_) p += 0.02 * Eigen::Vector2d(rng.Gaussian(), rng.Gaussian());
    options_.search_window_m = 2.5;
    options_.search_window_rad = Deg(10);
  }
  ClosestWallIndex index_;
  std::vector<Eigen::Vector2d> points_;
  RegistrationOptions options_;
};

TEST_F(OneWallOfTwoTest, IsAmbiguous) {
  const Se2 initial{0.0, {0.0, 1.0}};  // halfway between the walls
  const RegistrationResult r = Register(points_, {}, index_, initial, options_);
  ASSERT_TRUE(r.converged) << r.reason;
  EXPECT_GT(r.ambiguity, 0.9);
  EXPECT_LE(r.ambiguity, 1.0);
}

TEST_F(OneWallOfTwoTest, EqualPlacesAreToldApartByTheInitialGuess) {
  options_.search_tie_ratio = 0.9;
  // Either wall fits; the one nearer the guess wins, whichever side the guess is on.
  for (const double guess_y : {0.6, 1.4}) {
    SCOPED_TRACE(guess_y);
    const RegistrationResult r = Register(points_, {}, index_, Se2{0.0, {0.0, guess_y}}, options_);
    ASSERT_TRUE(r.converged) << r.reason;
    EXPECT_NEAR(r.T_plan_slam.t.y(), guess_y < 1 ? 0.0 : 2.0, 0.05);
    EXPECT_GT(r.ambiguity, 0.9);  // still ambiguous: the tracker waits for confirmation
  }
}

TEST(WallNormalShiftTest, SlidingAlongTheWallsIsNoShiftAcrossIsTheOffset) {
  const auto plan = MakeFloorPlan("corridor", {{{0, 0}, {20, 0}}, {{0, 2}, {20, 2}}});
  ASSERT_TRUE(plan.ok()) << plan.error;
  const ClosestWallIndex index(plan.plan);
  const FloorPlan seen{"", {{{5, 0}, {12, 0}}, {{5, 2}, {12, 2}}}, {}, {}, {}, {}, {}};
  const std::vector<Eigen::Vector2d> points = testing::SampleWalls(seen, 0.1);
  const Se2 at{0.0, {0.0, 0.0}};
  EXPECT_NEAR(WallNormalShift(points, index, at, Se2{0.0, {2.0, 0.0}}, 0.2), 0.0, 1e-9);
  EXPECT_NEAR(WallNormalShift(points, index, at, Se2{0.0, {1.5, 0.7}}, 0.2), 0.7, 1e-9);
  // Turned about the middle: each point moves across its wall by its lever arm.
  const double shift = WallNormalShift(points, index, at, Se2{Deg(2), {0.0, 0.0}}, 0.2);
  EXPECT_GT(shift, 0.1);
  EXPECT_LT(shift, 0.5);
}

TEST(RegistrationAmbiguityTest, CorridorSlidAlongItselfIsNotAnotherPlace) {
  // Both walls of a long corridor, no end in sight: every place along it fits equally,
  // but that is one place for the walls; the guess keeps its position along the axis.
  const auto plan = MakeFloorPlan("corridor", {{{0, 0}, {30, 0}}, {{0, 2}, {30, 2}}});
  ASSERT_TRUE(plan.ok()) << plan.error;
  const ClosestWallIndex index(plan.plan);
  const FloorPlan seen{"", {{{10, 0}, {16, 0}}, {{10, 2}, {16, 2}}}, {}, {}, {}, {}, {}};
  std::vector<Eigen::Vector2d> points = testing::SampleWalls(seen, 0.05);
  SplitMix64 rng(5);
  for (Eigen::Vector2d& p : points) p += 0.02 * Eigen::Vector2d(rng.Gaussian(), rng.Gaussian());
  RegistrationOptions options;
  options.method = RegistrationMethod::kIk;
  options.search_window_m = 2.5;
  options.search_window_rad = Deg(10);
  options.search_tie_ratio = 0.9;
  const Se2 guess{Deg(3), {1.2, 0.6}};
  const RegistrationResult r = Register(points, {}, index, guess, options);
  ASSERT_TRUE(r.converged) << r.reason;
  EXPECT_LT(r.ambiguity, 0.3);
  EXPECT_NEAR(r.T_plan_slam.theta, 0.0, Deg(0.3));
  EXPECT_NEAR(r.T_plan_slam.t.y(), 0.0, 0.05);
}

TEST(RegistrationAmbiguityTest, WholeRoomIsNotAmbiguous) {
  const FloorPlan plan = testing::AsymmetricRoom();
  const ClosestWallIndex index(plan);
  const Se2 truth{Deg(3), {0.5, -0.4}};  // T_plan_slam
  const std::vector<Eigen::Vector2d> points = SlamCloud(plan, truth.Inverse(), 0.02, 7);
  RegistrationOptions options;
  EXPECT_EQ(Register(points, {}, index, Se2{}, options).ambiguity, 0.0);  // no search
  options.search_window_m = 2.5;
  options.search_window_rad = Deg(10);
  const RegistrationResult r = Register(points, {}, index, Se2{}, options);
  ASSERT_TRUE(r.converged) << r.reason;
  EXPECT_THAT(r.T_plan_slam, IsNearlySe2(truth, 0.02, Deg(0.2)));
  EXPECT_LT(r.ambiguity, 0.3);
}

// A wall pick 65 m back with its heading 8 degrees off puts the room seen here 9 m off,
// onto the identical room next door: a search turning about the cloud finds that room,
// one turning about the pick's point (where its error is small) finds the right one.
TEST(RegistrationSearchTest, TurnsAboutThePivotWhereTheGuessIsKnownBest) {
  const FloorPlan room = testing::AsymmetricRoom();  // 10 x 7 m
  std::vector<Segment> rooms;
  for (int k = -2; k <= 2; ++k)
    for (const Segment& s : room.segments)
      rooms.push_back({s.a + Eigen::Vector2d(0, 9.0 * k), s.b + Eigen::Vector2d(0, 9.0 * k)});
  const FloorPlanParse plan = MakeFloorPlan("rooms", rooms);
  ASSERT_TRUE(plan.ok()) << plan.error;
  const ClosestWallIndex index(plan.plan);
  const std::vector<Eigen::Vector2d> points = SlamCloud(room, Se2{}, 0.02, 9);  // truth: identity
  const Eigen::Vector2d pick(69.7, 3.5);
  const Se2 guess = Se2{0.0, pick} * Se2{Deg(8), {0, 0}} * Se2{0.0, -pick};
  RegistrationOptions options;
  options.search_window_m = 2.5;
  options.search_window_rad = Deg(10);
  options.search_tie_ratio = 0.9;  // as the tracker: equal fits told apart by the guess
  const RegistrationResult about_cloud = Register(points, {}, index, guess, options);
  EXPECT_NEAR(about_cloud.T_plan_slam.t.y(), -9.0, 0.1);  // the room next door
  options.search_pivot = pick;
  const RegistrationResult about_pick = Register(points, {}, index, guess, options);
  ASSERT_TRUE(about_pick.converged) << about_pick.reason;
  EXPECT_THAT(about_pick.T_plan_slam, IsNearlySe2(Se2{}, 0.02, Deg(0.2)));
}

// Algorithm 4.6 alone: the walls' directions give the heading without any position. A
// room seen 6 degrees turned and 3 m off: the rotation found undoes the 6 degrees
// (whatever the offset), within a quarter of a degree; without normals, or with no plan
// wall near the cloud, there is nothing to turn by.
TEST(HoughRotationTest, WallDirectionsGiveTheHeadingWithoutAPlace) {
  const FloorPlan room = testing::AsymmetricRoom();
  const ClosestWallIndex index(room);
  const Cloud cloud = SlamCloudWithNormals(room, Se2{}, 0.01, 5);  // truth: identity
  HoughOptions h;
  h.max_rotation_rad = Deg(10);
  for (const Eigen::Vector2d& offset : {Eigen::Vector2d(0, 0), Eigen::Vector2d(3, -2)}) {
    const Se2 guess{Deg(6), offset};
    const std::optional<double> turn = HoughRotation(cloud.points, cloud.normals, index, guess, h);
    ASSERT_TRUE(turn.has_value());
    EXPECT_NEAR(*turn, Deg(-6), Deg(0.25)) << "offset " << offset.transpose();
  }
  EXPECT_FALSE(HoughRotation(cloud.points, {}, index, Se2{}, h).has_value());
  EXPECT_FALSE(HoughRotation(cloud.points, cloud.normals, index, Se2{0.0, {500, 500}}, h));
}

// A hall seen along one long wall and the foot of a cross wall: the guess is 2.4 m off
// along the hall, where nothing pinned it, and well known across it. The plan has the
// same corner again 2.4 m across the hall. With the guess's covariance the search looks
// only along the hall (the ellipse) and finds the right corner; every candidate it
// returns stays within the ellipse.
TEST(RegistrationSearchTest, CovarianceKeepsTheSearchInsideItsEllipse) {
  const std::vector<Segment> corner = {{{0, 0}, {20, 0}}, {{10, 0}, {10, 1.5}}};
  std::vector<Segment> walls = corner;
  for (const Segment& s : corner)
    walls.push_back({s.a + Eigen::Vector2d(0, -2.4), s.b + Eigen::Vector2d(0, -2.4)});
  const FloorPlanParse plan = MakeFloorPlan("halls", walls);
  ASSERT_TRUE(plan.ok()) << plan.error;
  const ClosestWallIndex index(plan.plan);
  std::vector<Eigen::Vector2d> points;  // truth: identity; 6 m of wall and the cross wall
  for (double x = 7; x <= 13; x += 0.05) points.emplace_back(x, 0);
  for (double y = 0.05; y <= 1.5; y += 0.05) points.emplace_back(10, y);
  const Se2 guess{0.0, {2.4, 0}};
  RegistrationOptions options;
  options.search_window_m = 2.5;
  options.search_window_rad = Deg(3);
  options.search_tie_ratio = 0.5;
  options.search_pivot = Eigen::Vector2d(12.4, 0.5);  // the wearer, by the guess
  // 1.5 m along the hall, 5 cm across it, a degree of heading.
  options.search_covariance = Eigen::Vector3d(Deg(1) * Deg(1), 1.5 * 1.5, 0.05 * 0.05).asDiagonal();
  options.search_max_sigmas = 3.0;
  for (const Se2& start : CorrelativeSearch(points, index, guess, options)) {
    const Eigen::Vector3d d = Difference(start, guess, *options.search_pivot);
    EXPECT_LE(std::abs(d(2)), 3 * 0.05 + 1e-9) << "across the hall: " << d.transpose();
  }
  const RegistrationResult r = Register(points, {}, index, guess, options);
  ASSERT_TRUE(r.converged) << r.reason;
  EXPECT_THAT(r.T_plan_slam, IsNearlySe2(Se2{}, 0.02, Deg(0.2)));
}

}  // namespace
}  // namespace floorpose
