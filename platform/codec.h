// Boundary of the daemon: protobuf payloads in, validated core types out. Every
// rejection comes with a reason for the log line; nothing here throws or aborts.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/frames.h"
#include "core/se2.h"
#include "core/tracking/alignment.h"
#include "floorpose/v1/config.pb.h"
#include "floorpose/v1/floorpose.pb.h"

namespace floorpose::platform {

// Why an input was refused as a whole (DaemonStatus.Counters has one counter each).
enum class Refusal {
  kMalformed,
  kUnknownEnum,
  kNonFinite,
  kOutOfRange,
  kOverLimits,
  kInconsistent,
  kFuture  // stamped too far ahead of the newest stamp taken (DeviceClock)
};

struct DecodedMesh {
  uint64_t mesh_id = 0;
  v1::MeshDelta::Change change = v1::MeshDelta::CHANGE_UNSPECIFIED;
  int64_t stamp_ns = 0;
  std::vector<Eigen::Vector3f> vertices;  // slam frame, world coordinates; NaN = unusable
  std::vector<uint32_t> triangles;
  size_t unusable_vertices = 0;  // non-finite or beyond the coordinate limit
};

// Returns an empty string on success, else why the delta was rejected as a whole (and, in
// *kind, which sort of refusal that is).
std::string DecodeMeshDelta(const std::string& payload, HeadsetFrame frame,
                            const v1::LimitsConfig& limits, DecodedMesh* out,
                            Refusal* kind = nullptr);

struct DecodedPose {
  int64_t stamp_ns = 0;
  Pose2 pose_slam;
  v1::HeadsetPose::TrackingState tracking = v1::HeadsetPose::TRACKING_UNSPECIFIED;
  v1::HeadsetPose::Odometry odometry = v1::HeadsetPose::VISUAL_INERTIAL;  // never UNSPECIFIED
};

std::string DecodeHeadsetPose(const std::string& payload, HeadsetFrame frame,
                              const v1::LimitsConfig& limits, DecodedPose* out,
                              Refusal* kind = nullptr);

std::string DecodeCommand(const std::string& payload, v1::Command* out);

// What the daemon publishes, as messages: a registration's (an update's polish)
// statistics, a reliability, a state, an alignment's source, and the Alignment message
// of an alignment on `floor` (with its polish's statistics when it has them).
v1::RegistrationStats ToProto(const RegistrationResult& r);
v1::Reliability::Flag ToProto(ReliabilityFlag f);
v1::Reliability ToProto(const Reliability& r);
v1::DaemonStatus::State ToProto(TrackState s);
v1::Alignment::Source ToProto(AlignmentSource s);
v1::Alignment ToProto(const AlignmentState& a, const std::string& floor);

}  // namespace floorpose::platform
