// SE(2) rigid transforms, named by their frames: T_plan_slam maps slam points to plan.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace floorpose {

inline double WrapAngle(double a) {
  a = std::fmod(a + M_PI, 2.0 * M_PI);
  if (a < 0) a += 2.0 * M_PI;
  return a - M_PI;
}

struct Se2 {
  double theta = 0.0;  // radians, counter-clockwise
  Eigen::Vector2d t = Eigen::Vector2d::Zero();

  static Se2 Identity() { return {}; }
  Eigen::Matrix2d R() const {
    const double c = std::cos(theta), s = std::sin(theta);
    return (Eigen::Matrix2d() << c, -s, s, c).finished();
  }
  Eigen::Vector2d operator*(const Eigen::Vector2d& p) const { return R() * p + t; }
  Se2 operator*(const Se2& o) const { return {WrapAngle(theta + o.theta), R() * o.t + t}; }
  Se2 Inverse() const { return {WrapAngle(-theta), -(R().transpose() * t)}; }
};

// A pose of the headset projected on the horizontal plane, plus its height.
struct Pose2 {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  double heading = 0.0;  // radians, direction the wearer faces
  double z = 0.0;        // height, metres
};

// Perturbations of T_plan_slam about a pivot on the plan (normally the wearer), so that
// they say directly how far the wearer moves (u) and turns (phi):
//   delta = (phi, u):  x -> R(phi) (x - pivot) + pivot + u
// The perturbation that takes `from` to `to`: to = Exp(delta) from.
inline Eigen::Vector3d Difference(const Se2& to, const Se2& from, const Eigen::Vector2d& pivot) {
  const Eigen::Vector2d u = to * (from.Inverse() * pivot) - pivot;
  return {WrapAngle(to.theta - from.theta), u.x(), u.y()};
}
// Exp(delta) * T.
inline Se2 Perturb(const Se2& T, const Eigen::Vector3d& delta, const Eigen::Vector2d& pivot) {
  Se2 E;
  E.theta = delta(0);
  E.t = pivot + delta.tail<2>() - E.R() * pivot;
  return E * T;
}

inline Pose2 Apply(const Se2& T_b_a, const Pose2& pose_a) {
  return {T_b_a * pose_a.position, WrapAngle(pose_a.heading + T_b_a.theta), pose_a.z};
}

}  // namespace floorpose
