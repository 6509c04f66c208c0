// The payload of a DDS sample (platform::Envelope) through the daemon's decoding and
// validation, platform/codec.h, for every input topic; also a recording's record, as
// `floorpose replay` and `eval` read it.
//
// Input: byte 0 chooses what the rest is: bits 0-1 the kind (MeshDelta, HeadsetPose,
// Command, RecordingRecord), bit 2 the headset frame, bit 3 tight limits (so that the
// over-limit paths are reachable with small inputs).
#include <google/protobuf/stubs/logging.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include "platform/codec.h"
#include "platform/dds.h"
#include "platform/recording.h"

namespace floorpose::platform {
namespace {

// What the decoders promise beyond "no crash": broken promises abort, like a crash.
void Check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "codec_fuzzer: broken promise: %s\n", what);
  std::abort();
}

void DecodeMesh(const std::string& payload, HeadsetFrame frame, const v1::LimitsConfig& limits) {
  DecodedMesh mesh;
  if (!DecodeMeshDelta(payload, frame, limits, &mesh).empty()) return;
  Check(mesh.change != v1::MeshDelta::CHANGE_UNSPECIFIED, "mesh accepted without a change");
  Check(mesh.vertices.size() <= limits.max_vertices_per_mesh(), "vertex limit");
  Check(mesh.triangles.size() % 3 == 0, "triangles not in threes");
  Check(mesh.triangles.size() / 3 <= limits.max_triangles_per_mesh(), "triangle limit");
  size_t unusable = 0;
  for (const Eigen::Vector3f& v : mesh.vertices) {
    if (v.hasNaN()) {
      ++unusable;
    } else {
      Check(v.allFinite() && v.cwiseAbs().maxCoeff() <= limits.max_abs_coordinate_m(),
            "usable vertex out of range");
    }
  }
  Check(unusable == mesh.unusable_vertices, "unusable vertices miscounted");
}

void DecodePose(const std::string& payload, HeadsetFrame frame, const v1::LimitsConfig& limits) {
  DecodedPose pose;
  if (!DecodeHeadsetPose(payload, frame, limits, &pose).empty()) return;
  Check(pose.pose_slam.position.allFinite() && std::isfinite(pose.pose_slam.heading) &&
            std::isfinite(pose.pose_slam.z),
        "accepted pose not finite");
}

void Decode(Topic topic, const std::string& payload, HeadsetFrame frame,
            const v1::LimitsConfig& limits) {
  switch (topic) {
    case Topic::kMeshDelta: DecodeMesh(payload, frame, limits); break;
    case Topic::kHeadsetPose: DecodePose(payload, frame, limits); break;
    case Topic::kCommand: {
      v1::Command command;
      if (DecodeCommand(payload, &command).empty())
        Check(command.command_case() != v1::Command::COMMAND_NOT_SET, "empty command accepted");
      break;
    }
    default: break;  // the daemon's own outputs: it never decodes them
  }
}

}  // namespace
}  // namespace floorpose::platform

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  google::protobuf::SetLogHandler(nullptr);  // "invalid UTF-8" for every other input
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace floorpose;
  using namespace floorpose::platform;
  if (size == 0) return 0;
  const uint8_t selector = data[0];
  const std::string payload(reinterpret_cast<const char*>(data + 1), size - 1);
  const HeadsetFrame frame =
      selector & 4 ? HeadsetFrame::kRightHandedZUp : HeadsetFrame::kUnityLeftHandedYUp;
  v1::LimitsConfig limits;
  if (selector & 8) {
    limits.set_max_vertices_per_mesh(8);
    limits.set_max_triangles_per_mesh(4);
    limits.set_max_abs_coordinate_m(10);
  }
  switch (selector & 3) {
    case 0: Decode(Topic::kMeshDelta, payload, frame, limits); break;
    case 1: Decode(Topic::kHeadsetPose, payload, frame, limits); break;
    case 2: Decode(Topic::kCommand, payload, frame, limits); break;
    case 3: {
      // One record of a recording: the topic name says how to decode its envelope.
      v1::RecordingRecord record;
      if (!record.ParseFromString(payload)) break;
      const std::optional<Topic> topic = TopicFromName(record.topic());
      if (!topic) break;
      const Envelope envelope = FromProto(record.envelope());
      Decode(*topic, envelope.payload, frame, limits);
      break;
    }
  }
  return 0;
}
