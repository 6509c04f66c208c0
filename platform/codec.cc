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

// A mesh's arrays whole triangles and vertices, within the limits; an error or empty.
std::string CheckMeshSizes(const v1::MeshDelta& msg, const v1::LimitsConfig& limits,
                           const std::string& what, Refusal& k) {
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
  return {};
}

// The mesh-to-world transform: identity when absent, else 16 finite values of an affine
// matrix (row-major); an error or empty.
std::string MeshToWorld(const v1::MeshDelta& msg, const std::string& what, Refusal& k,
                        Eigen::Matrix4d* T_world_mesh) {
  T_world_mesh->setIdentity();
  if (msg.mesh_to_world_size() == 0) return {};
  if (msg.mesh_to_world_size() != 16)
    return Refuse(
        k, Refusal::kInconsistent,
        what + ": mesh-to-world needs 16 values, got " + std::to_string(msg.mesh_to_world_size()));
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) (*T_world_mesh)(r, c) = msg.mesh_to_world(r * 4 + c);
  if (!T_world_mesh->allFinite())
    return Refuse(k, Refusal::kNonFinite, what + ": non-finite mesh-to-world transform");
  if ((T_world_mesh->row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-6)
    return Refuse(k, Refusal::kInconsistent,
                  what + ": mesh-to-world is not affine (last row must be 0 0 0 1)");
  return {};
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
  if (std::string e = CheckMeshSizes(msg, limits, what, k); !e.empty()) return e;
  Eigen::Matrix4d T_world_mesh;
  if (std::string e = MeshToWorld(msg, what, k, &T_world_mesh); !e.empty()) return e;
  // Vertices in the SLAM frame; one that is not finite or beyond the coordinate limit is
  // kept as NaN (its triangles are dropped later) and counted.
  const Eigen::Matrix4d T = MeshToWorldToSlam(frame, T_world_mesh);
  const double max_abs = limits.max_abs_coordinate_m();
  const size_t nv = static_cast<size_t>(msg.vertices_size()) / 3;
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

v1::RegistrationStats ToProto(const RegistrationResult& r) {
  v1::RegistrationStats s;
  s.set_method(r.method);
  s.set_converged(r.converged);
  s.set_iterations(r.iterations);
  s.set_points(r.points);
  s.set_inliers(r.inliers);
  s.set_inlier_rmse_m(r.inlier_rmse);
  s.set_rmse_m(r.rmse);
  for (int i = 0; i < 3; ++i) s.add_normal_eigenvalues(r.eigenvalues(i));
  s.set_time_ms(r.time_ms);
  s.set_reason(r.reason);
  return s;
}

v1::Reliability::Flag ToProto(ReliabilityFlag f) {
  switch (f) {
    case ReliabilityFlag::kReliable: return v1::Reliability::RELIABLE;
    case ReliabilityFlag::kDegraded: return v1::Reliability::DEGRADED;
    case ReliabilityFlag::kUnreliable: return v1::Reliability::UNRELIABLE;
  }
  return v1::Reliability::FLAG_UNSPECIFIED;
}

v1::Reliability ToProto(const Reliability& r) {
  v1::Reliability out;
  out.set_flag(ToProto(r.flag));
  out.set_probability(r.probability);
  out.set_rmse_m(r.rmse_m);
  out.set_reason(r.reason);
  return out;
}

v1::DaemonStatus::State ToProto(TrackState s) {
  switch (s) {
    case TrackState::kWaitingForPlan: return v1::DaemonStatus::WAITING_FOR_PLAN;
    case TrackState::kWaitingForAlignment: return v1::DaemonStatus::WAITING_FOR_ALIGNMENT;
    case TrackState::kTracking: return v1::DaemonStatus::TRACKING;
    case TrackState::kDegraded: return v1::DaemonStatus::DEGRADED;
    case TrackState::kLost: return v1::DaemonStatus::LOST;
  }
  return v1::DaemonStatus::STATE_UNSPECIFIED;
}

v1::Alignment::Source ToProto(AlignmentSource s) {
  switch (s) {
    case AlignmentSource::kWallPick: return v1::Alignment::WALL_PICK;
    case AlignmentSource::kFlip: return v1::Alignment::FLIP;
    case AlignmentSource::kRegistration: return v1::Alignment::REGISTRATION;
    case AlignmentSource::kGlobalSearch: return v1::Alignment::GLOBAL_SEARCH;
    case AlignmentSource::kNone: break;
  }
  return v1::Alignment::SOURCE_UNSPECIFIED;
}

// The Alignment message of an alignment on `floor` (with its registration's statistics
// when it has them): published on every change and kept in the state snapshot.
v1::Alignment ToProto(const AlignmentState& a, const std::string& floor) {
  v1::Alignment out;
  out.mutable_t_plan_slam()->set_theta(a.T_plan_slam.theta);
  out.mutable_t_plan_slam()->set_x(a.T_plan_slam.t.x());
  out.mutable_t_plan_slam()->set_y(a.T_plan_slam.t.y());
  out.set_version(a.version);
  out.set_source(ToProto(a.source));
  out.set_floor(floor);
  out.set_stamp_ns(a.stamp_ns);
  if (a.registration) {
    *out.mutable_stats() = ToProto(*a.registration);
    out.mutable_stats()->set_accepted(true);
  }
  return out;
}

}  // namespace floorpose::platform
