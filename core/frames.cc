#include "core/frames.h"

#include <cmath>

namespace floorpose {
namespace {

// The y/z swap; its own inverse.
Eigen::Matrix3d SwapYZ() { return (Eigen::Matrix3d() << 1, 0, 0, 0, 0, 1, 0, 1, 0).finished(); }

}  // namespace

std::optional<HeadsetFrame> ParseHeadsetFrame(std::string_view name) {
  if (name == "unity") return HeadsetFrame::kUnityLeftHandedYUp;
  if (name == "zup") return HeadsetFrame::kRightHandedZUp;
  return std::nullopt;
}

Eigen::Vector3d PointToSlam(HeadsetFrame frame, const Eigen::Vector3d& p) {
  if (frame == HeadsetFrame::kRightHandedZUp) return p;
  return {p.x(), p.z(), p.y()};
}

Eigen::Quaterniond OrientationToSlam(HeadsetFrame frame, const Eigen::Quaterniond& q) {
  if (frame == HeadsetFrame::kRightHandedZUp) return q;
  // (w, v) -> (w, -P v), see the header.
  return Eigen::Quaterniond(q.w(), -q.x(), -q.z(), -q.y());
}

Pose2 HeadsetPoseToSlam(HeadsetFrame frame, const Eigen::Vector3d& p_headset,
                        const Eigen::Quaterniond& q_headset) {
  const Eigen::Vector3d p = PointToSlam(frame, p_headset);
  const Eigen::Quaterniond q = OrientationToSlam(frame, q_headset).normalized();
  // The viewing direction in the device's own axes: Unity's +z is slam's +y after the
  // swap; a Z-up device looks along +x.
  const Eigen::Vector3d forward_device = frame == HeadsetFrame::kUnityLeftHandedYUp
                                             ? Eigen::Vector3d::UnitY()
                                             : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d forward = q * forward_device;
  Pose2 pose;
  pose.position = p.head<2>();
  pose.z = p.z();
  // Looking straight up or down leaves no horizontal direction; keep 0 then.
  pose.heading = forward.head<2>().norm() > 1e-9 ? std::atan2(forward.y(), forward.x()) : 0.0;
  return pose;
}

Eigen::Matrix4d MeshToWorldToSlam(HeadsetFrame frame, const Eigen::Matrix4d& T) {
  if (frame == HeadsetFrame::kRightHandedZUp) return T;
  Eigen::Matrix4d P = Eigen::Matrix4d::Identity();
  P.topLeftCorner<3, 3>() = SwapYZ();
  return P * T * P;
}

}  // namespace floorpose
