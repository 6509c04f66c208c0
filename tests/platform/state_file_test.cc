// The state snapshot: the file (atomic, checked) and the Engine's state in it, saved and
// resumed; corrupt, foreign and out-of-range snapshots refused with the reason.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/sim/demo_walk.h"
#include "platform/engine.h"
#include "platform/state_file.h"
#include "tests/test_util.h"
#include "tools/lib/headset_messages.h"

namespace floorpose::platform {
namespace {

constexpr HeadsetFrame kFrame = HeadsetFrame::kUnityLeftHandedYUp;

class StateFileTest : public testing::TempDirTest {
 protected:
  std::string Read(const std::string& path) const {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  v1::StateSnapshot Sample() const {
    v1::StateSnapshot s;
    s.set_device_id("hl-1");
    s.set_plan_path("/plans/a.geojson");
    s.mutable_alignment()->set_version(3);
    v1::StateSnapshot::Mesh* m = s.add_meshes();
    m->set_mesh_id(7);
    for (float v : {1.0f, 2.0f}) m->add_points(v);
    for (float v : {0.0f, 1.0f}) m->add_normals(v);
    return s;
  }
};

TEST_F(StateFileTest, RoundTripsAndLeavesNoTemporaryFile) {
  const std::string path = Path("hl-1.snapshot");
  std::string error;
  ASSERT_TRUE(WriteStateFile(path, Sample(), &error)) << error;
  v1::StateSnapshot back;
  ASSERT_EQ(ReadStateFile(path, &back, &error), StateRead::kOk) << error;
  EXPECT_EQ(back.SerializeAsString(), Sample().SerializeAsString());
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  // Overwriting replaces it whole.
  v1::StateSnapshot other = Sample();
  other.clear_meshes();
  ASSERT_TRUE(WriteStateFile(path, other, &error)) << error;
  ASSERT_EQ(ReadStateFile(path, &back, &error), StateRead::kOk) << error;
  EXPECT_EQ(back.meshes_size(), 0);
}

TEST_F(StateFileTest, MissingIsNotAnError) {
  v1::StateSnapshot s;
  std::string error;
  EXPECT_EQ(ReadStateFile(Path("none.snapshot"), &s, &error), StateRead::kMissing);
  EXPECT_TRUE(error.empty());
}

TEST_F(StateFileTest, CorruptTruncatedAndForeignFilesAreRefusedWithTheReason) {
  const std::string path = Path("hl-1.snapshot");
  std::string error;
  ASSERT_TRUE(WriteStateFile(path, Sample(), &error)) << error;
  const std::string good = Read(path);
  struct Case {
    std::string bytes, reason;
  };
  std::string flipped = good;
  flipped[flipped.size() - 3] ^= 0x01;
  std::string garbage_payload = good.substr(0, 20);
  garbage_payload += std::string(good.size() - 20, '\xff');
  const std::vector<Case> cases = {
      {"", "no FPSNAP1 header"},
      {"{\"type\": \"FeatureCollection\"}", "no FPSNAP1 header"},
      {good.substr(0, good.size() - 1), "truncated"},
      {good + "x", "truncated or padded"},
      {flipped, "checksum mismatch"},
      {garbage_payload, "checksum mismatch"},
  };
  for (const Case& c : cases) {
    Write("hl-1.snapshot", c.bytes);
    v1::StateSnapshot s;
    error.clear();
    EXPECT_EQ(ReadStateFile(path, &s, &error), StateRead::kBad) << c.reason;
    EXPECT_NE(error.find(c.reason), std::string::npos) << error;
  }
}

TEST_F(StateFileTest, OnlyARegularFileWithinTheLimitIsRead) {
  namespace fs = std::filesystem;
  std::string error;
  const std::string good = Path("good.snapshot");
  ASSERT_TRUE(WriteStateFile(good, Sample(), &error)) << error;
  const std::string link = Path("link.snapshot"), dir = Path("dir.snapshot"),
                    fifo = Path("fifo.snapshot");
  fs::create_symlink(good, link);
  fs::create_directory(dir);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const auto& [path, reason] : {std::pair{link, "a symbolic link, not followed"},
                                     {dir, "a directory, not a file"},
                                     {fifo, "a FIFO, not a file"}}) {
    v1::StateSnapshot s;
    error.clear();
    EXPECT_EQ(ReadStateFile(path, &s, &error), StateRead::kBad) << path;
    EXPECT_EQ(error, reason);
  }
  v1::StateSnapshot s;
  error.clear();
  EXPECT_EQ(ReadStateFile(good, &s, &error, /*max_bytes=*/8), StateRead::kBad);
  EXPECT_NE(error.find("over limits.max_snapshot_mb"), std::string::npos) << error;
  error.clear();
  EXPECT_EQ(ReadStateFile(good, &s, &error), StateRead::kOk) << error;
  // A link left where the temporary file goes is replaced, not written through.
  const std::string victim = Write("victim", "keep me");
  fs::create_symlink(victim, good + ".tmp");
  ASSERT_TRUE(WriteStateFile(good, Sample(), &error)) << error;
  EXPECT_EQ(Read(victim), "keep me");
}

TEST_F(StateFileTest, OneDaemonPerStateDirectory) {
  std::string error;
  auto first = StateDirLock::Take(dir_.string(), &error);
  ASSERT_TRUE(first) << error;
  EXPECT_FALSE(StateDirLock::Take(dir_.string(), &error));
  EXPECT_NE(error.find("is in use by another floorposed (pid " + std::to_string(::getpid()) + ")"),
            std::string::npos)
      << error;
  first.reset();
  EXPECT_TRUE(StateDirLock::Take(dir_.string(), &error)) << error;
}

TEST_F(StateFileTest, SetAsideMovesTheFileOutOfTheWay) {
  const std::string path = Write("hl-1.snapshot", "junk");
  std::string error;
  const std::string aside = SetAside(path, &error);
  ASSERT_FALSE(aside.empty()) << error;
  EXPECT_EQ(aside.rfind(path + ".bad-", 0), 0u) << aside;
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_EQ(Read(aside), "junk");
}

TEST(SnapshotPathTest, KeepsTheDeviceIdInsideTheDirectory) {
  EXPECT_EQ(SnapshotPath("/var/lib/floorposed", "hololens-1"),
            "/var/lib/floorposed/hololens-1.snapshot");
  EXPECT_EQ(SnapshotPath("/s", "../../etc/passwd"), "/s/device.._.._etc_passwd.snapshot");
  EXPECT_EQ(SnapshotPath("/s", ""), "/s/device.snapshot");
}

// An Engine driven through a wall pick and a walk, registrations run in line.
class EngineStateTest : public testing::TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    plan_ = testing::AsymmetricRoom();
    config_.set_plan_path(Write("room.txt", testing::ThesisText(plan_)));
    config_.mutable_dds()->set_device_id("hl-1");
  }
  std::unique_ptr<Engine> NewEngine(std::vector<v1::PlanPose>* poses = nullptr) {
    auto engine = std::make_unique<Engine>(
        config_,
        [poses](Topic topic, const google::protobuf::Message& m) {
          if (poses && topic == Topic::kPlanPose)
            poses->push_back(static_cast<const v1::PlanPose&>(m));
        },
        [] { return int64_t{0}; });
    EXPECT_EQ(engine->Start(), "");
    return engine;
  }
  static Envelope Wrap(const google::protobuf::Message& m, int64_t stamp_ns) {
    Envelope e;
    e.device_id = "hl-1";
    e.stamp_ns = stamp_ns;
    m.SerializeToString(&e.payload);
    return e;
  }
  static void Step(Engine& engine, const sim::SimStep& step) {
    for (const sim::SimMesh& m : step.meshes)
      engine.OnMeshDelta(Wrap(tools::ToMeshDelta(m, kFrame, step.stamp_ns), step.stamp_ns));
    engine.OnHeadsetPose(
        Wrap(tools::ToHeadsetPose(step.slam, kFrame, step.stamp_ns), step.stamp_ns));
    if (auto job = engine.TakeDueJob())
      engine.OnRegistrationDone(RunJob(std::move(*job), [] { return int64_t{0}; }));
  }
  // Walks the first half of a walk through the room after a wall pick.
  sim::DemoWalk WalkInto(Engine& engine) {
    sim::DemoWalkOptions o;
    o.pick_point_error_m = 0.3;
    const sim::DemoWalk walk =
        sim::SimulateDemoWalk(plan_, {{1.5, 1.5}, {2.5, 5.5}, {6.0, 6.0}, {8.8, 2.0}}, o);
    engine.OnCommand(Wrap(tools::ToWallPickCommand(walk, kFrame, 1), 0));
    EXPECT_GE(walk.steps.size(), 30u);
    for (size_t k = 0; k < walk.steps.size() / 2; ++k) Step(engine, walk.steps[k]);
    return walk;
  }

  FloorPlan plan_;
  v1::FloorposedConfig config_;
};

TEST_F(EngineStateTest, ARestoredEngineGoesOnExactlyWhereTheSavedOneWas) {
  std::vector<v1::PlanPose> poses_a, poses_b;
  auto a = NewEngine(&poses_a);
  const sim::DemoWalk walk = WalkInto(*a);
  ASSERT_GE(a->counters().registrations_accepted(), 1u);
  const v1::StateSnapshot saved = a->SaveState();

  auto b = NewEngine(&poses_b);
  ASSERT_EQ(b->RestoreState(saved), "");
  const AlignmentState& before = a->tracker().alignment();
  const AlignmentState& after = b->tracker().alignment();
  EXPECT_EQ(after.version, before.version);
  EXPECT_EQ(after.source, before.source);
  EXPECT_EQ(after.T_plan_slam.theta, before.T_plan_slam.theta);
  EXPECT_EQ(after.T_plan_slam.t, before.T_plan_slam.t);
  EXPECT_EQ(b->store().points(), a->store().points());
  EXPECT_EQ(b->store().meshes(), a->store().meshes());
  const v1::StateSnapshot again = b->SaveState();
  EXPECT_EQ(again.latest_stamp_ns(), saved.latest_stamp_ns());
  EXPECT_EQ(again.next_version(), saved.next_version());
  // The belief resumes as it was: its samples, its doubt, checked (not doubted again).
  ASSERT_TRUE(saved.checked());
  EXPECT_TRUE(again.checked());
  EXPECT_EQ(again.elsewhere(), saved.elsewhere());
  ASSERT_GT(saved.samples_size(), 0);
  EXPECT_EQ(again.samples_size(), saved.samples_size());
  for (int i = 0; i < saved.samples_size(); ++i) ASSERT_EQ(again.samples(i), saved.samples(i));
  EXPECT_EQ(b->reliability().flag, a->reliability().flag) << b->reliability().reason;
  EXPECT_NEAR(b->reliability().probability, a->reliability().probability, 0.01);

  // The same next pose gives the same plan pose.
  const sim::SimStep& next = walk.steps[walk.steps.size() / 2];
  Step(*a, next);
  Step(*b, next);
  ASSERT_FALSE(poses_b.empty());
  EXPECT_EQ(poses_b.back().x(), poses_a.back().x());
  EXPECT_EQ(poses_b.back().y(), poses_a.back().y());
  EXPECT_EQ(poses_b.back().alignment_version(), poses_a.back().alignment_version());
}

TEST_F(EngineStateTest, ForeignOrBrokenSnapshotsAreRefusedAndNothingOfThemIsKept) {
  auto a = NewEngine();
  WalkInto(*a);
  const v1::StateSnapshot saved = a->SaveState();
  struct Case {
    std::string reason;
    std::function<void(v1::StateSnapshot*)> spoil;
  };
  const std::vector<Case> cases = {
      {"of device 'hl-2'", [](v1::StateSnapshot* s) { s->set_device_id("hl-2"); }},
      {"before it changed", [](v1::StateSnapshot* s) { s->set_plan_digest(s->plan_digest() + 1); }},
      {"does not load now", [](v1::StateSnapshot* s) { s->set_plan_path("/nonexistent.geojson"); }},
      {"not finite or out of range",
       [](v1::StateSnapshot* s) { s->mutable_meshes(0)->set_points(0, std::nanf("")); }},
      {"malformed", [](v1::StateSnapshot* s) { s->mutable_meshes(0)->add_points(1.0f); }},
      {"out of range", [](v1::StateSnapshot* s) { s->mutable_meshes(0)->set_points(1, 5e21f); }},
      {"alignment or its belief out of range",
       [](v1::StateSnapshot* s) { s->set_covariance(4, 1e300); }},
      {"not symmetric and positive", [](v1::StateSnapshot* s) { s->set_covariance(0, -1.0); }},
      {"without the belief's covariance", [](v1::StateSnapshot* s) { s->clear_covariance(); }},
      {"belief samples malformed", [](v1::StateSnapshot* s) { s->add_samples(1.0); }},
      {"belief samples that are not finite",
       [](v1::StateSnapshot* s) { s->set_samples(1, std::nan("")); }},
      {"versions out of order", [](v1::StateSnapshot* s) { s->set_next_version(1); }},
      {"alignment or its belief out of range", [](v1::StateSnapshot* s) {
         s->mutable_alignment()->mutable_t_plan_slam()->set_x(INFINITY);
       }}};
  for (const Case& c : cases) {
    v1::StateSnapshot spoilt = saved;
    c.spoil(&spoilt);
    auto b = NewEngine();
    const std::string error = b->RestoreState(spoilt);
    EXPECT_NE(error.find(c.reason), std::string::npos) << c.reason << ": " << error;
    EXPECT_FALSE(b->tracker().has_alignment()) << c.reason;
    EXPECT_EQ(b->store().points(), 0u) << c.reason;
    EXPECT_TRUE(b->tracker().has_plan()) << c.reason << ": the configured plan stays";
  }
}

}  // namespace
}  // namespace floorpose::platform
