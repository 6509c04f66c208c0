#include "platform/codec.h"

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

namespace floorpose::platform {
namespace {

bool Finite(double v) { return std::isfinite(v); }

std::string Refuse(Refusal& kind, Refusal what, std::string why) {
  kind = what;
  return why;
}

// The engine and tracker subtract stamps and windows from stamps; within +-2^62 ns (146
// years either side of the clock's zero) no such difference overflows int64.
constexpr int64_t kMaxAbsStampNs = int64_t{1} << 62;
bool StampInRange(int64_t stamp_ns) {
  return stamp_ns > -kMaxAbsStampNs && stamp_ns < kMaxAbsStampNs;
}

}  // namespace

std::string DecodeMeshDelta(const std::string& payload, HeadsetFrame frame,
                            const v1::LimitsConfig& limits, DecodedMesh* out, Refusal* kind) {
  Refusal ignored;
  Refusal& k = kind ? *kind : ignored;
  v1::MeshDelta msg;
  if (!msg.ParseFromString(payload))
    return Refuse(k, Refusal::kMalformed, "malformed MeshDelta protobuf");
  if (!v1::MeshDelta::Change_IsValid(msg.change()) ||
      msg.change() == v1::MeshDelta::CHANGE_UNSPECIFIED) {
    return Refuse(k, Refusal::kUnknownEnum,
                  "MeshDelta " + std::to_string(msg.mesh_id()) + ": unknown change " +
                      std::to_string(static_cast<int>(msg.change())));
  }
  if (!StampInRange(msg.stamp_ns()))
    return Refuse(k, Refusal::kOutOfRange,
                  "MeshDelta " + std::to_string(msg.mesh_id()) + ": stamp_ns " +
                      std::to_string(msg.stamp_ns()) + " out of range");
  *out = {};
  out->mesh_id = msg.mesh_id();
  out->change = msg.change();
  out->stamp_ns = msg.stamp_ns();
  if (msg.change() == v1::MeshDelta::REMOVED) return {};

  const std::string what = "MeshDelta " + std::to_string(msg.mesh_id());
  if (msg.vertices_size() % 3 != 0)
    return Refuse(k, Refusal::kInconsistent, what + ": vertex array not a multiple of 3");
  if (msg.triangles_size() % 3 != 0)
    return Refuse(k, Refusal::kInconsistent, what + ": index array not a multiple of 3");
  const size_t nv = static_cast<size_t>(msg.vertices_size()) / 3;
  const size_t nt = static_cast<size_t>(msg.triangles_size()) / 3;
  if (nv > limits.max_vertices_per_mesh())
    return Refuse(k, Refusal::kOverLimits,
                  what + ": " + std::to_string(nv) + " vertices over the limit of " +
                      std::to_string(limits.max_vertices_per_mesh()));
  if (nt > limits.max_triangles_per_mesh())
    return Refuse(k, Refusal::kOverLimits,
                  what + ": " + std::to_string(nt) + " triangles over the limit of " +
                      std::to_string(limits.max_triangles_per_mesh()));

  Eigen::Matrix4d T_world_mesh = Eigen::Matrix4d::Identity();
  if (msg.mesh_to_world_size() == 16) {
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) T_world_mesh(r, c) = msg.mesh_to_world(r * 4 + c);
    if (!T_world_mesh.allFinite())
      return Refuse(k, Refusal::kNonFinite, what + ": non-finite mesh-to-world transform");
    if ((T_world_mesh.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-6)
      return Refuse(k, Refusal::kInconsistent,
                    what + ": mesh-to-world is not affine (last row must be 0 0 0 1)");
  } else if (msg.mesh_to_world_size() != 0) {
    return Refuse(
        k, Refusal::kInconsistent,
        what + ": mesh-to-world needs 16 values, got " + std::to_string(msg.mesh_to_world_size()));
  }
  const Eigen::Matrix4d T = MeshToWorldToSlam(frame, T_world_mesh);
  const double max_abs = limits.max_abs_coordinate_m();
  out->vertices.resize(nv);
  for (size_t i = 0; i < nv; ++i) {
    const Eigen::Vector3d v(msg.vertices(static_cast<int>(3 * i)),
                            msg.vertices(static_cast<int>(3 * i + 1)),
                            msg.vertices(static_cast<int>(3 * i + 2)));
    const Eigen::Vector3d w =
        T.topLeftCorner<3, 3>() * PointToSlam(frame, v) + T.topRightCorner<3, 1>();
    if (!w.allFinite() || w.cwiseAbs().maxCoeff() > max_abs) {
      out->vertices[i] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
      ++out->unusable_vertices;
    } else {
      out->vertices[i] = w.cast<float>();
    }
  }
  out->triangles.assign(msg.triangles().begin(), msg.triangles().end());
  return {};
}

std::string DecodeHeadsetPose(const std::string& payload, HeadsetFrame frame,
                              const v1::LimitsConfig& limits, DecodedPose* out, Refusal* kind) {
  Refusal ignored;
  Refusal& k = kind ? *kind : ignored;
  v1::HeadsetPose msg;
  if (!msg.ParseFromString(payload))
    return Refuse(k, Refusal::kMalformed, "malformed HeadsetPose protobuf");
  if (!v1::HeadsetPose::TrackingState_IsValid(msg.tracking()))
    return Refuse(
        k, Refusal::kUnknownEnum,
        "HeadsetPose: unknown tracking state " + std::to_string(static_cast<int>(msg.tracking())));
  if (!v1::HeadsetPose::Odometry_IsValid(msg.odometry()))
    return Refuse(
        k, Refusal::kUnknownEnum,
        "HeadsetPose: unknown odometry " + std::to_string(static_cast<int>(msg.odometry())));
  if (!StampInRange(msg.stamp_ns()))
    return Refuse(k, Refusal::kOutOfRange,
                  "HeadsetPose: stamp_ns " + std::to_string(msg.stamp_ns()) + " out of range");
  const auto& p = msg.position();
  const auto& q = msg.orientation();
  if (!Finite(p.x()) || !Finite(p.y()) || !Finite(p.z()) || !Finite(q.x()) || !Finite(q.y()) ||
      !Finite(q.z()) || !Finite(q.w()))
    return Refuse(k, Refusal::kNonFinite, "HeadsetPose: non-finite position or orientation");
  const double max_abs = limits.max_abs_coordinate_m();
  if (std::abs(p.x()) > max_abs || std::abs(p.y()) > max_abs || std::abs(p.z()) > max_abs)
    return Refuse(k, Refusal::kOutOfRange,
                  "HeadsetPose: position beyond " + std::to_string(max_abs) + " m");
  const Eigen::Quaterniond quat(q.w(), q.x(), q.y(), q.z());
  if (std::abs(quat.norm() - 1.0) > 0.01)
    return Refuse(k, Refusal::kOutOfRange,
                  "HeadsetPose: orientation is not a unit quaternion (norm " +
                      std::to_string(quat.norm()) + ")");
  out->stamp_ns = msg.stamp_ns();
  out->tracking = msg.tracking();
  out->odometry = msg.odometry() == v1::HeadsetPose::ODOMETRY_UNSPECIFIED
                      ? v1::HeadsetPose::VISUAL_INERTIAL
                      : msg.odometry();
  out->pose_slam = HeadsetPoseToSlam(frame, {p.x(), p.y(), p.z()}, quat);
  return {};
}

std::string DecodeCommand(const std::string& payload, v1::Command* out) {
  if (!out->ParseFromString(payload)) return "malformed Command protobuf";
  if (out->command_case() == v1::Command::COMMAND_NOT_SET) return "Command without a command";
  return {};
}

}  // namespace floorpose::platform
