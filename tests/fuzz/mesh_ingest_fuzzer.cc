// A headset session made of fuzz input through a real platform::Engine on a small floor
// plan: mesh deltas (the wall extractor and the wall store see arbitrary meshes), poses,
// commands, raw payloads, and the registrations the engine asks for, run inline as
// `floorpose eval` runs them (so the tracker sees whatever registration makes of them).
//
// Input: a sequence of operations, each one byte then its operands (tests/fuzz/
// make_corpus.py writes the seeds; a missing operand reads as 0):
//   0 mesh     header (bits 0-1 change, 2 raw float vertices, 3 transform, 4-7 mesh id),
//              vertex count, triangle count, [16 floats], vertices (int16 cm or float),
//              triangles (one byte per index), stamp step
//   1 pose     x y z (int16 cm, Unity frame: y up), yaw (1/256 turn), tracking, stamp step
//   2 command  kind (wall pick, flip, reset, get state, load plan, none), operands
//   3 raw      topic (mesh, pose, command, another device's mesh), length, payload bytes
// A stamp step is a byte: n < 255 moves the clock n x 10 ms on, 255 sets it to the next
// 8 bytes (so stamps can jump back or to the extremes a sender could put in a sample).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "platform/config.h"
#include "platform/engine.h"
#include "tests/fuzz/fuzz_room.h"

namespace floorpose::platform {
namespace {

using fuzz::kDevice;

class Input {
 public:
  Input(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool empty() const { return pos_ >= size_; }
  uint8_t Byte() { return empty() ? 0 : data_[pos_++]; }
  template <typename T>
  T Raw() {
    uint8_t bytes[sizeof(T)] = {};
    for (uint8_t& b : bytes) b = Byte();
    T v;
    std::memcpy(&v, bytes, sizeof v);
    return v;
  }
  double Metres() { return Raw<int16_t>() * 0.01; }
  std::string Bytes(size_t n) {
    std::string out;
    while (n-- > 0 && !empty()) out.push_back(static_cast<char>(Byte()));
    return out;
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

class Session {
 public:
  explicit Session(const v1::FloorposedConfig& config)
      : engine_(
            config, [](Topic, const google::protobuf::Message&) {}, [this] { return stamp_; }) {}

  bool Start() { return engine_.Start().empty(); }

  void Step(Input& in) {
    switch (in.Byte() & 3) {
      case 0: Mesh(in); break;
      case 1: Pose(in); break;
      case 2: Command(in); break;
      case 3: Raw(in); break;
    }
    if (auto job = engine_.TakeDueJob())
      engine_.OnRegistrationDone(RunJob(std::move(*job), [this] { return stamp_; }));
  }

  void Finish() {
    engine_.Status("");
    engine_.StatusLine();
  }

 private:
  Envelope Wrap(const google::protobuf::Message& m, const char* device = kDevice) {
    return {device, ++seq_, stamp_, m.SerializeAsString()};
  }

  void Tick(Input& in) {
    const uint8_t step = in.Byte();
    // Wraps rather than overflows (UB): the extremes are the engine's to survive, not ours.
    stamp_ = step == 255
                 ? in.Raw<int64_t>()
                 : static_cast<int64_t>(static_cast<uint64_t>(stamp_) + step * 10'000'000ull);
  }

  void Mesh(Input& in) {
    const uint8_t header = in.Byte();
    const int vertices = in.Byte(), triangles = in.Byte();
    v1::MeshDelta m;
    m.set_change(static_cast<v1::MeshDelta::Change>(header & 3));
    m.set_mesh_id(header >> 4);
    if (header & 8)
      for (int i = 0; i < 16; ++i) m.add_mesh_to_world(in.Raw<float>());
    for (int i = 0; i < 3 * vertices; ++i)
      m.add_vertices(header & 4 ? in.Raw<float>() : static_cast<float>(in.Metres()));
    for (int i = 0; i < 3 * triangles; ++i) m.add_triangles(in.Byte());
    Tick(in);
    m.set_stamp_ns(stamp_);
    engine_.OnMeshDelta(Wrap(m));
  }

  void Pose(Input& in) {
    v1::HeadsetPose p;
    p.mutable_position()->set_x(in.Metres());
    p.mutable_position()->set_y(in.Metres());
    p.mutable_position()->set_z(in.Metres());
    const double yaw = in.Byte() * (2 * M_PI / 256);
    p.mutable_orientation()->set_y(std::sin(yaw / 2));  // about Unity's up axis
    p.mutable_orientation()->set_w(std::cos(yaw / 2));
    p.set_tracking(static_cast<v1::HeadsetPose::TrackingState>(in.Byte() & 3));
    Tick(in);
    p.set_stamp_ns(stamp_);
    engine_.OnHeadsetPose(Wrap(p));
  }

  void Command(Input& in) {
    v1::Command c;
    c.set_request_id(++seq_);
    switch (in.Byte() % 6) {
      case 0: {
        auto* pick = c.mutable_wall_pick();
        pick->mutable_headset_point()->set_x(in.Metres());
        pick->mutable_headset_point()->set_y(in.Metres());
        pick->mutable_headset_point()->set_z(in.Metres());
        const double yaw = in.Byte() * (2 * M_PI / 256);
        pick->mutable_headset_normal()->set_x(std::sin(yaw));
        pick->mutable_headset_normal()->set_z(std::cos(yaw));
        pick->set_plan_x(in.Metres());
        pick->set_plan_y(in.Metres());
        const double heading = in.Byte() * (2 * M_PI / 256);
        pick->set_plan_normal_x(std::cos(heading));
        pick->set_plan_normal_y(std::sin(heading));
        break;
      }
      case 1: c.mutable_flip(); break;
      case 2: c.mutable_reset(); break;
      case 3: c.mutable_get_state(); break;
      case 4: c.mutable_load_plan()->set_plan_id(in.Byte() & 1 ? "room" : "../room"); break;
      case 5: break;  // no command: refused
    }
    engine_.OnCommand(Wrap(c));
  }

  // Bytes as a sender could put them in a sample, stamps and all.
  void Raw(Input& in) {
    const uint8_t topic = in.Byte();
    Envelope e{kDevice, ++seq_, stamp_, in.Bytes(in.Raw<uint16_t>())};
    switch (topic & 3) {
      case 0: engine_.OnMeshDelta(e); break;
      case 1: engine_.OnHeadsetPose(e); break;
      case 2: engine_.OnCommand(e); break;
      case 3:
        e.device_id = "another-headset";
        engine_.OnMeshDelta(e);
        break;
    }
  }

  Engine engine_;
  int64_t stamp_ = 1'000'000'000;
  uint64_t seq_ = 0;
};

v1::FloorposedConfig MakeConfig() {
  v1::FloorposedConfig config;
  config.mutable_dds()->set_device_id(kDevice);
  config.set_plan_path((fuzz::WorkDir() / "room.geojson").string());
  config.set_plan_dir(fuzz::WorkDir().string());
  // Smaller than the daemon's limits, so that one input stays fast (an input over them
  // takes the same rejection path as a larger one would in the daemon).
  config.mutable_limits()->set_max_wall_points_per_mesh(20000);
  config.mutable_limits()->set_max_wall_points(50000);
  // Updates in smaller windows and beliefs: the same code, at a tenth of the cost.
  config.mutable_walls()->set_window_max_points(1000);
  config.mutable_tracking()->mutable_samples()->set_min_samples(100);
  config.mutable_tracking()->mutable_samples()->set_max_samples(300);
  return config;
}

}  // namespace
}  // namespace floorpose::platform

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  using namespace floorpose::platform;
  floorpose::fuzz::SetUp("mesh-ingest-fuzzer");
  const std::string invalid = ValidateConfig(MakeConfig());
  if (!invalid.empty()) {
    std::fprintf(stderr, "mesh_ingest_fuzzer: bad config: %s\n", invalid.c_str());
    std::abort();
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace floorpose::platform;
  static const floorpose::v1::FloorposedConfig config = MakeConfig();
  Session session(config);
  if (!session.Start()) {
    std::fprintf(stderr, "mesh_ingest_fuzzer: the built-in plan did not load\n");
    std::abort();
  }
  Input in(data, size);
  while (!in.empty()) session.Step(in);
  session.Finish();
  return 0;
}
