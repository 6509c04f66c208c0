// A participant of its own process for the DDS Security tests: Cyclone keeps one security
// configuration per domain and process, so an intruder must be another process. It
// publishes a wall mesh, a pose and a get_state command for a device five times a second,
// listens, and prints what came back from a daemon:
//
//   dds_peer DOMAIN DEVICE SECONDS [IDENTITY_DIR NAME]
//   -> "plan_poses N status S replies R"
//
// Or it forges a daemon's output: 20 PlanPose samples for DEVICE (x = 999, RELIABLE),
// written once a reader matched (or after 3 s):
//
//   dds_peer --forge DOMAIN DEVICE IDENTITY_DIR NAME
//   -> "forged N" (samples written) or "refused WHY" (DDS would not make the writer)
//
// Or it feeds a daemon 20 HeadsetPose samples for DEVICE in a partition of its choice
// ("-": the default one), as a headset of another device might try:
//
//   dds_peer --feed PARTITION DOMAIN DEVICE IDENTITY_DIR NAME
//   -> "forged N" or "refused WHY"
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "platform/dds.h"
#include "tools/lib/headset_link.h"
#include "tools/lib/headset_messages.h"

namespace {

// Writes 20 samples of `topic` for `device` (a PlanPose at x = 999, or a HeadsetPose)
// in `partitions`.
int Forge(floorpose::platform::Topic topic, const std::vector<std::string>& partitions,
          uint32_t domain, const std::string& device, const std::string& dir,
          const std::string& name) {
  using namespace floorpose;
  const platform::DdsSecurity identity = platform::SecurityFilesIn(dir, name);
  platform::Participant participant(domain, platform::LoopbackCycloneConfig(), &identity);
  std::unique_ptr<platform::Writer> writer;
  try {
    writer = std::make_unique<platform::Writer>(participant, topic, partitions);
  } catch (const std::exception& e) {
    std::printf("refused %s\n", e.what());
    return 0;
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  while (writer->MatchedReaders() == 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  int written = 0;
  for (int i = 0; i < 20; ++i) {
    const int64_t stamp = 1'000'000'000 + i * 300'000'000LL;
    v1::PlanPose forged;
    forged.set_source_stamp_ns(stamp);
    forged.set_x(999);
    forged.mutable_reliability()->set_flag(v1::Reliability::RELIABLE);
    const std::string payload = topic == platform::Topic::kPlanPose
                                    ? forged.SerializeAsString()
                                    : tools::ToHeadsetPose(Pose2{{1.0, 2.0}, 0.0, 1.6},
                                                           HeadsetFrame::kUnityLeftHandedYUp, stamp)
                                          .SerializeAsString();
    platform::Envelope e{device, writer->NextSeq(), stamp, payload, 0};
    written += writer->Write(e);
  }
  writer->WaitForAcks(std::chrono::seconds(2));
  std::printf("forged %d\n", written);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace floorpose;
  if (argc == 6 && std::string(argv[1]) == "--forge") {
    try {
      return Forge(platform::Topic::kPlanPose, {},
                   static_cast<uint32_t>(std::strtoul(argv[2], nullptr, 10)), argv[3], argv[4],
                   argv[5]);
    } catch (const std::exception& e) {
      std::printf("error %s\n", e.what());
      return 1;
    }
  }
  if (argc == 7 && std::string(argv[1]) == "--feed") {
    const std::string partition = argv[2];
    try {
      return Forge(platform::Topic::kHeadsetPose, {partition == "-" ? std::string() : partition},
                   static_cast<uint32_t>(std::strtoul(argv[3], nullptr, 10)), argv[4], argv[5],
                   argv[6]);
    } catch (const std::exception& e) {
      std::printf("error %s\n", e.what());
      return 1;
    }
  }
  if (argc != 4 && argc != 6) {
    std::fprintf(stderr, "usage: dds_peer DOMAIN DEVICE SECONDS [IDENTITY_DIR NAME]\n");
    return 2;
  }
  const auto domain = static_cast<uint32_t>(std::strtoul(argv[1], nullptr, 10));
  const double seconds = std::strtod(argv[3], nullptr);
  platform::DdsSecurity identity;
  if (argc == 6) identity = platform::SecurityFilesIn(argv[4], argv[5]);
  try {
    tools::HeadsetLink link(domain, platform::LoopbackCycloneConfig(), argv[2],
                            argc == 6 ? &identity : nullptr);
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000));
    int64_t stamp = 1'000'000'000;
    // A 2 x 2.5 m wall (headset frame: Unity, y up), re-sent as UPDATED.
    v1::MeshDelta wall;
    wall.set_mesh_id(1);
    wall.set_change(v1::MeshDelta::UPDATED);
    for (float v : {0.f, 0.f, 1.f, 2.f, 0.f, 1.f, 2.f, 2.5f, 1.f, 0.f, 2.5f, 1.f})
      wall.add_vertices(v);
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) wall.add_triangles(i);
    v1::Command get_state;
    get_state.mutable_get_state();
    get_state.set_request_id(1);
    while (std::chrono::steady_clock::now() < deadline) {
      link.Send(platform::Topic::kHeadsetPose,
                tools::ToHeadsetPose(Pose2{{1.0, 2.0}, 0.0, 1.6}, HeadsetFrame::kUnityLeftHandedYUp,
                                     stamp),
                stamp);
      link.Send(platform::Topic::kCommand, get_state, 0);
      wall.set_stamp_ns(stamp);
      link.Send(platform::Topic::kMeshDelta, wall, stamp);
      stamp += 300'000'000;
      link.WaitUntil([] { return false; }, std::chrono::milliseconds(200));
    }
    link.Poll();
    std::printf("plan_poses %zu status %d replies %zu\n", link.plan_poses.size(),
                link.status.has_value() ? 1 : 0, link.replies.size());
  } catch (const std::exception& e) {
    std::printf("error %s\n", e.what());
    return 1;
  }
  return 0;
}
