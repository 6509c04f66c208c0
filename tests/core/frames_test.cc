// Headset (Unity: left-handed, Y up) to slam (right-handed, Z up). The expected values
// come from the matrix rule p_slam = P p, R_slam = P R P (P swaps y and z), never from
// the quaternion shortcut the code uses.
#include "core/frames.h"

#include <gtest/gtest.h>

#include "core/random.h"
#include "tests/test_util.h"

namespace floorpose {
namespace {

using testing::Deg;
using testing::RandomRotation;
using testing::RandomVector3;

constexpr auto kUnity = HeadsetFrame::kUnityLeftHandedYUp;
constexpr auto kZUp = HeadsetFrame::kRightHandedZUp;

Eigen::Matrix3d P() { return (Eigen::Matrix3d() << 1, 0, 0, 0, 0, 1, 0, 1, 0).finished(); }

// Heading of a slam-frame direction, as the code defines it: atan2 of the horizontal part.
double HeadingOf(const Eigen::Vector3d& d) { return std::atan2(d.y(), d.x()); }

TEST(FramesTest, ParseHeadsetFrame) {
  EXPECT_EQ(ParseHeadsetFrame("unity"), kUnity);
  EXPECT_EQ(ParseHeadsetFrame("zup"), kZUp);
  EXPECT_FALSE(ParseHeadsetFrame("Unity").has_value());
  EXPECT_FALSE(ParseHeadsetFrame("").has_value());
}

TEST(FramesTest, PointsSwapYAndZ) {
  SplitMix64 rng(11);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3d p = RandomVector3(rng, -50, 50);
    const Eigen::Vector3d s = PointToSlam(kUnity, p);
    EXPECT_EQ(s, Eigen::Vector3d(p.x(), p.z(), p.y()));
    EXPECT_EQ(PointToSlam(kZUp, p), p);
  }
  // Unity's up (+y) is slam's up (+z); Unity's forward (+z) is slam's +y.
  EXPECT_EQ(PointToSlam(kUnity, Eigen::Vector3d::UnitY()), Eigen::Vector3d::UnitZ());
  EXPECT_EQ(PointToSlam(kUnity, Eigen::Vector3d::UnitZ()), Eigen::Vector3d::UnitY());
}

TEST(FramesTest, OrientationMatchesMatrixRuleForRandomRotations) {
  SplitMix64 rng(12);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Quaterniond q = RandomRotation(rng);
    const Eigen::Matrix3d expected = P() * q.toRotationMatrix() * P();
    const Eigen::Matrix3d R = OrientationToSlam(kUnity, q).toRotationMatrix();
    ASSERT_TRUE(R.isApprox(expected, 1e-12)) << "rotation " << i << "\n"
                                             << R << "\nvs\n"
                                             << expected;
    // A proper rotation: orthonormal with determinant +1 (P alone has det -1).
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
    EXPECT_TRUE((R * R.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
    // Rotating a converted point equals converting the rotated point.
    const Eigen::Vector3d p = RandomVector3(rng, -5, 5);
    EXPECT_TRUE((R * PointToSlam(kUnity, p)).isApprox(PointToSlam(kUnity, q * p), 1e-12));
  }
}

TEST(FramesTest, ZUpOrientationIsUnchanged) {
  SplitMix64 rng(13);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Quaterniond q = RandomRotation(rng);
    EXPECT_TRUE(OrientationToSlam(kZUp, q).isApprox(q, 1e-15));
  }
}

TEST(FramesTest, IdentityUnityCameraLooksAlongSlamPlusY) {
  // Unity's camera looks along its +z, which is slam +y: heading +90 degrees.
  const Pose2 pose =
      HeadsetPoseToSlam(kUnity, Eigen::Vector3d(1, 2, 3), Eigen::Quaterniond::Identity());
  EXPECT_NEAR(pose.heading, Deg(90), 1e-12);
  EXPECT_EQ(pose.position, Eigen::Vector2d(1, 3));
  EXPECT_EQ(pose.z, 2.0);  // Unity y is the height
}

TEST(FramesTest, IdentityZUpCameraLooksAlongPlusX) {
  const Pose2 pose =
      HeadsetPoseToSlam(kZUp, Eigen::Vector3d(1, 2, 3), Eigen::Quaterniond::Identity());
  EXPECT_NEAR(pose.heading, 0.0, 1e-12);
  EXPECT_EQ(pose.position, Eigen::Vector2d(1, 2));
  EXPECT_EQ(pose.z, 3.0);
}

TEST(FramesTest, UnityYawTurnsClockwiseSeenFromAbove) {
  // Yaw by +a about Unity +y: q = (cos(a/2), 0, sin(a/2), 0). Its matrix sends the view
  // direction e_z to (sin a, 0, cos a); P makes that (sin a, cos a, 0) in slam, so the
  // heading is atan2(cos a, sin a) = 90 deg - a: a positive Unity yaw turns the wearer
  // clockwise seen from above (Unity's left-handed rotation).
  for (double a_deg = -180; a_deg <= 180; a_deg += 7.5) {
    const double a = Deg(a_deg);
    const Eigen::Quaterniond q(std::cos(a / 2), 0, std::sin(a / 2), 0);
    const Eigen::Vector3d forward_slam = P() * (q.toRotationMatrix() * Eigen::Vector3d::UnitZ());
    const double expected = HeadingOf(forward_slam);
    EXPECT_NEAR(WrapAngle(expected - (Deg(90) - a)), 0.0, 1e-12);  // the closed form
    const Pose2 pose = HeadsetPoseToSlam(kUnity, Eigen::Vector3d::Zero(), q);
    EXPECT_NEAR(WrapAngle(pose.heading - expected), 0.0, 1e-9) << "yaw " << a_deg << " deg";
  }
  // Concretely: +90 deg yaw turns from slam +y (north) to slam +x (east).
  const Eigen::Quaterniond q90(std::cos(Deg(45)), 0, std::sin(Deg(45)), 0);
  EXPECT_NEAR(HeadsetPoseToSlam(kUnity, Eigen::Vector3d::Zero(), q90).heading, 0.0, 1e-12);
}

TEST(FramesTest, HeadingOfRandomOrientationsFollowsMatrixRule) {
  SplitMix64 rng(14);
  int checked = 0;
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Quaterniond q = RandomRotation(rng);
    const Eigen::Vector3d p = RandomVector3(rng, -20, 20);
    const Eigen::Vector3d forward_slam = P() * (q.toRotationMatrix() * Eigen::Vector3d::UnitZ());
    if (forward_slam.head<2>().norm() < 1e-3) continue;  // looking straight up or down
    ++checked;
    const Pose2 pose = HeadsetPoseToSlam(kUnity, p, q);
    EXPECT_NEAR(WrapAngle(pose.heading - HeadingOf(forward_slam)), 0.0, 1e-9);
    EXPECT_EQ(pose.position, Eigen::Vector2d(p.x(), p.z()));
    EXPECT_EQ(pose.z, p.y());
  }
  EXPECT_GT(checked, 990);
}

TEST(FramesTest, HeadingIgnoresQuaternionScale) {
  // The decoder accepts quaternions within 1% of unit norm; the heading must not care.
  SplitMix64 rng(15);
  for (int i = 0; i < 50; ++i) {
    const Eigen::Quaterniond q = RandomRotation(rng);
    Eigen::Quaterniond scaled = q;
    scaled.coeffs() *= 1.009;
    EXPECT_NEAR(HeadsetPoseToSlam(kUnity, Eigen::Vector3d::Zero(), scaled).heading,
                HeadsetPoseToSlam(kUnity, Eigen::Vector3d::Zero(), q).heading, 1e-9);
  }
}

TEST(FramesTest, StraightUpGivesZeroHeadingNotNaN) {
  // Pitch -90 deg about Unity +x sends the view direction e_z to +y (up).
  const Eigen::Quaterniond up(Eigen::AngleAxisd(Deg(-90), Eigen::Vector3d::UnitX()));
  ASSERT_TRUE((up * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  const Pose2 pose = HeadsetPoseToSlam(kUnity, Eigen::Vector3d::Zero(), up);
  EXPECT_EQ(pose.heading, 0.0);
}

TEST(FramesTest, MeshToWorldConsistentWithPointToSlam) {
  SplitMix64 rng(16);
  for (int i = 0; i < 200; ++i) {
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    T.topLeftCorner<3, 3>() = RandomRotation(rng).toRotationMatrix();
    T.topRightCorner<3, 1>() = RandomVector3(rng, -30, 30);
    const Eigen::Matrix4d T_slam = MeshToWorldToSlam(kUnity, T);
    EXPECT_TRUE(T_slam.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)));
    const Eigen::Matrix3d R_slam = T_slam.topLeftCorner<3, 3>();
    EXPECT_NEAR(R_slam.determinant(), 1.0, 1e-12);
    for (int k = 0; k < 5; ++k) {
      const Eigen::Vector3d v_mesh = RandomVector3(rng, -3, 3);
      // Transform in the headset frame then convert == convert then transform in slam.
      const Eigen::Vector3d want = PointToSlam(kUnity, (T * v_mesh.homogeneous()).head<3>());
      const Eigen::Vector3d got = (T_slam * PointToSlam(kUnity, v_mesh).homogeneous()).head<3>();
      EXPECT_TRUE(got.isApprox(want, 1e-12)) << got.transpose() << " vs " << want.transpose();
    }
    EXPECT_EQ(MeshToWorldToSlam(kZUp, T), T);
  }
}

}  // namespace
}  // namespace floorpose
