// The state snapshot a restarted floorposed reads (platform/state_file.h, Engine::
// RestoreState): a file on disk a crash, a disk error or a person may have spoilt.
//
// Input: byte 0 picks the way in, the rest is
//   even: a whole snapshot file, read as the daemon reads it at start;
//   odd:  a StateSnapshot payload given straight to RestoreState with the device, plan
//         and plan digest of the running engine put in, so that the fuzzer gets past the
//         checksum and the identity checks to the values themselves.
// A restored engine then takes a pose, a mesh and a registration, and saves its state
// again, as the daemon would go on after a restart.

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "platform/engine.h"
#include "platform/state_file.h"
#include "tests/fuzz/fuzz_room.h"

namespace floorpose::platform {
namespace {

using fuzz::kDevice;

v1::FloorposedConfig MakeConfig() {
  v1::FloorposedConfig config;
  config.mutable_dds()->set_device_id(kDevice);
  config.set_plan_path((fuzz::WorkDir() / "room.geojson").string());
  config.mutable_limits()->set_max_wall_points(50000);
  config.mutable_walls()->set_window_max_points(1000);
  return config;
}

Envelope Wrap(const google::protobuf::Message& m, int64_t stamp_ns) {
  return {kDevice, 1, stamp_ns, m.SerializeAsString()};
}

// What the daemon does next: a pose, a wall in front of it, a registration if due.
void GoOn(Engine& engine, int64_t stamp_ns) {
  v1::HeadsetPose pose;
  pose.set_stamp_ns(stamp_ns);
  pose.mutable_position()->set_x(3.0);
  pose.mutable_position()->set_y(1.6);
  pose.mutable_position()->set_z(2.0);
  pose.mutable_orientation()->set_w(1.0);
  engine.OnHeadsetPose(Wrap(pose, stamp_ns));
  v1::MeshDelta wall;
  wall.set_mesh_id(1000);
  wall.set_change(v1::MeshDelta::ADDED);
  wall.set_stamp_ns(stamp_ns);
  for (float v : {0.f, 0.f, 4.f, 6.f, 0.f, 4.f, 6.f, 2.5f, 4.f, 0.f, 2.5f, 4.f})
    wall.add_vertices(v);
  for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) wall.add_triangles(i);
  engine.OnMeshDelta(Wrap(wall, stamp_ns));
  if (auto job = engine.TakeDueJob())
    engine.OnRegistrationDone(RunJob(std::move(*job), [] { return int64_t{0}; }));
  engine.SaveState();
  engine.Status("");
}

}  // namespace
}  // namespace floorpose::platform

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  floorpose::fuzz::SetUp("snapshot-fuzzer");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace floorpose::platform;
  if (size == 0) return 0;
  static const floorpose::v1::FloorposedConfig config = MakeConfig();
  Engine engine(
      config, [](Topic, const google::protobuf::Message&) {}, [] { return int64_t{0}; });
  if (!engine.Start().empty()) {
    std::fprintf(stderr, "snapshot_fuzzer: the built-in plan did not load\n");
    std::abort();
  }
  const std::string rest(reinterpret_cast<const char*>(data) + 1, size - 1);
  floorpose::v1::StateSnapshot snapshot;
  if (data[0] % 2 == 0) {
    const std::string path = (floorpose::fuzz::WorkDir() / "state.snapshot").string();
    std::ofstream(path, std::ios::binary | std::ios::trunc) << rest;
    std::string error;
    if (ReadStateFile(path, &snapshot, &error) != StateRead::kOk) return 0;
  } else {
    if (!snapshot.ParseFromString(rest)) return 0;
    const floorpose::v1::StateSnapshot own = engine.SaveState();
    snapshot.set_device_id(own.device_id());
    snapshot.set_plan_path(own.plan_path());
    snapshot.set_plan_digest(own.plan_digest());
    snapshot.set_floor(own.floor());
  }
  const std::string error = engine.RestoreState(snapshot);
  // Refused or not, the engine goes on: restored, or clean with the configured plan.
  if (!error.empty() && !engine.tracker().has_plan()) {
    std::fprintf(stderr, "snapshot_fuzzer: a refused snapshot took the plan away: %s\n",
                 error.c_str());
    std::abort();
  }
  GoOn(engine, snapshot.latest_stamp_ns() > 0 && snapshot.latest_stamp_ns() < (int64_t{1} << 61)
                   ? snapshot.latest_stamp_ns() + 300'000'000
                   : 1'000'000'000);
  return 0;
}
