// Headset frame to slam frame, converted once at ingest (docs/protocol.md, "Frames").
//
// Unity (the HoloLens app) is left-handed with Y up and the camera looking along +z.
// floorpose works right-handed with Z up. Swapping y and z is a reflection P (det -1):
// points map as p_slam = P p_headset, rotations as R_slam = P R_headset P. A rotation
// by angle a about axis u becomes a rotation by -a about P u, so a quaternion
// (w, v) maps to (w, -P v).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string_view>

#include "core/se2.h"

namespace floorpose {

enum class HeadsetFrame {
  kUnityLeftHandedYUp,  // HoloLens / Unity: x right, y up, z forward
  kRightHandedZUp,      // already slam convention: x forward, z up
};

std::optional<HeadsetFrame> ParseHeadsetFrame(std::string_view name);

Eigen::Vector3d PointToSlam(HeadsetFrame frame, const Eigen::Vector3d& p_headset);
Eigen::Quaterniond OrientationToSlam(HeadsetFrame frame, const Eigen::Quaterniond& q_headset);

// Horizontal pose (position, heading of the viewing direction, height) in slam.
Pose2 HeadsetPoseToSlam(HeadsetFrame frame, const Eigen::Vector3d& p_headset,
                        const Eigen::Quaterniond& q_headset);

// 4x4 mesh-to-world transform (headset convention) as a slam-frame transform.
Eigen::Matrix4d MeshToWorldToSlam(HeadsetFrame frame, const Eigen::Matrix4d& T_world_mesh);

}  // namespace floorpose
