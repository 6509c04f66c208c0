// Hostile input and broken state (label hostile): a real floorposed process attacked over
// loopback DDS by a participant of the attacker's own, and fed broken files. Each test is
// one row of docs/robustness.md.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <iterator>
#include <tuple>

#include "platform/state_file.h"
#include "tests/integration/daemon_fixture.h"

namespace floorpose {
namespace {

constexpr int64_t kPoisonNs = (int64_t{1} << 62) - 1;  // inside the documented +-2^62

class HostileTest : public DaemonTest {
 protected:
  // A participant of the attacker's own that publishes as the wearer's device.
  tools::HeadsetLink& Attacker() {
    if (!attacker_) {
      attacker_ = std::make_unique<tools::HeadsetLink>(domain_, platform::LoopbackCycloneConfig(),
                                                       "hl-test");
      EXPECT_TRUE(attacker_->WaitForDaemon(seconds(15)));
    }
    return *attacker_;
  }
  // Starts a fresh floorposed (a new process, nothing kept) and forgets the outputs seen.
  void FreshDaemon() {
    if (daemon_ && daemon_->Running()) {
      ASSERT_EQ(daemon_->Terminate(seconds(2)), 0);
    }
    link_->plan_poses.clear();
    link_->alignments.clear();
    link_->status.reset();
    meshes_sent_ = 0;
    LaunchDaemon();
    ASSERT_TRUE(link_->WaitForDaemon(seconds(15))) << "floorposed did not come back";
  }
  // Walks `walk` after its wall pick, its stamps mapped by `stamp`, running before(k)
  // before step k; returns the RELIABLE share of the plan poses from step `from` on.
  // Steps go in lockstep with the daemon, so that it takes the inputs in the order sent
  // whatever the load: a step's pose once the daemon has taken the step's mesh deltas
  // (and any the attacker sent, counted in meshes_sent_), the next step once the pose is
  // answered. A large delta's fragment resent under load would otherwise reach the
  // daemon after the pose sent after it, and the update would weigh one scan less.
  double Walk(
      const sim::DemoWalk& walk, size_t from, const std::function<int64_t(int64_t)>& stamp,
      const std::function<void(size_t)>& before = [](size_t) {}) {
    link_->Send(Topic::kCommand, tools::ToWallPickCommand(walk, kFrame, 1), 0);
    EXPECT_TRUE(link_->WaitUntil([&] { return !link_->alignments.empty(); }, seconds(10)));
    for (size_t k = 0; k < walk.steps.size(); ++k) {
      before(k);
      const sim::SimStep& step = walk.steps[k];
      const int64_t t = stamp(step.stamp_ns);
      for (const sim::SimMesh& m : step.meshes)
        link_->Send(Topic::kMeshDelta, tools::ToMeshDelta(m, kFrame, t), t);
      meshes_sent_ += step.meshes.size();
      EXPECT_TRUE(WaitForStatus([&](const v1::DaemonStatus& st) {
        return st.counters().mesh_deltas_in() >= meshes_sent_;
      })) << "the daemon did not take all "
          << meshes_sent_ << " mesh deltas sent";
      link_->Send(Topic::kHeadsetPose, tools::ToHeadsetPose(step.slam, kFrame, t), t);
      EXPECT_TRUE(link_->WaitUntil([&] { return link_->plan_poses.size() > k; }, seconds(10)))
          << "no answer to pose " << k;
    }
    EXPECT_TRUE(link_->WaitUntil([&] { return link_->plan_poses.size() >= walk.steps.size(); },
                                 seconds(10)))
        << link_->plan_poses.size() << " plan poses of " << walk.steps.size();
    size_t reliable = 0, all = 0;
    for (size_t k = from; k < link_->plan_poses.size(); ++k, ++all)
      reliable += link_->plan_poses[k].reliability().flag() == v1::Reliability::RELIABLE;
    return all ? 100.0 * static_cast<double>(reliable) / static_cast<double>(all) : 0.0;
  }
  static int64_t Same(int64_t t) { return t; }
  uint64_t Registrations() {
    link_->WaitUntil([] { return false; }, std::chrono::milliseconds(300));
    return link_->status ? link_->status->counters().registrations() : 0;
  }

  std::unique_ptr<tools::HeadsetLink> attacker_;
  uint64_t meshes_sent_ = 0;  // mesh deltas sent to the daemon since it started
};

// 1. One pose and one mesh delta stamped 2^62-1 used to make every later message "older
// than the newest taken": no registration ran again, and reset did not help.
TEST_F(HostileTest, StampsFromTheFarFutureAreRefusedAndTheWalkGoesOn) {
  // Deterministic: the two walks are compared update for update, whatever the load.
  StartDaemon("deterministic: true\n");
  const sim::DemoWalk walk = DaemonTest::Walk(/*pick_error_m=*/0.3, 5);
  const size_t third = walk.steps.size() / 3;
  const double clean = Walk(walk, third, Same);

  ASSERT_NO_FATAL_FAILURE(FreshDaemon());
  uint64_t registrations_at_attack = 0;
  // The poisoned pose before step `third`, the poisoned mesh before the next one.
  const double attacked = Walk(walk, third, Same, [&](size_t k) {
    if (k != third && k != third + 1) return;
    if (k == third) registrations_at_attack = Registrations();
    const sim::SimStep& step = walk.steps[k];
    tools::HeadsetLink& a = Attacker();
    if (k == third) {
      a.Send(Topic::kHeadsetPose, tools::ToHeadsetPose(step.slam, kFrame, kPoisonNs), kPoisonNs);
      // Refused before the mesh comes: two stamps as far ahead in a row are taken as the
      // headset's clock jumping, and a busy daemon would read both in one batch.
      EXPECT_TRUE(WaitForStatus(
          [](const v1::DaemonStatus& st) { return st.counters().future_stamps() >= 1; }));
    } else {
      sim::SimMesh mesh;  // the latest scan, as a new mesh
      for (size_t j = 0; j < k; ++j)
        if (!walk.steps[j].meshes.empty()) mesh = walk.steps[j].meshes.back();
      ASSERT_FALSE(mesh.vertices_slam.empty());
      mesh.id += 1'000'000;
      a.Send(Topic::kMeshDelta, tools::ToMeshDelta(mesh, kFrame, kPoisonNs), kPoisonNs);
      ++meshes_sent_;
    }
    a.WaitUntil([] { return false; }, std::chrono::milliseconds(100));
  });
  std::printf("RELIABLE after step %zu: %.1f%% clean, %.1f%% with the poisoned stamps\n", third,
              clean, attacked);
  // The daemon is deterministic given its inputs' order, and Walk keeps that order.
  EXPECT_EQ(attacked, clean);
  EXPECT_GT(Registrations(), registrations_at_attack) << "no registration after the attack";
  ASSERT_TRUE(link_->status);
  EXPECT_EQ(link_->status->counters().future_stamps(), 2u);
  EXPECT_EQ(link_->status->counters().clock_restarts(), 0u);
  EXPECT_NE(Log().find("from the future"), std::string::npos);
}

// 2. A headset whose app restarted (stamps begin again at 0) used to be dropped as
// "older than the newest taken" for the rest of the walk.
TEST_F(HostileTest, AHeadsetWhoseClockStartsAgainIsTrackedAsBefore) {
  StartDaemon("deterministic: true\n");
  const sim::DemoWalk walk = DaemonTest::Walk(/*pick_error_m=*/0.3, 6);
  const size_t half = walk.steps.size() / 2;
  const int64_t restart_ns = walk.steps[half].stamp_ns;
  Walk(walk, half, Same);
  const std::vector<v1::PlanPose> clean = link_->plan_poses;

  ASSERT_NO_FATAL_FAILURE(FreshDaemon());
  // An app restarts in seconds: the old clock's poses are all answered before the new
  // clock's come (Walk's lockstep; a busy daemon would read both in one batch, sorted by
  // stamp). The new clock follows at once: the daemon's timeline goes on by the time it
  // saw pass, and a silence longer than motion.lost_after_s (1.5 s) is a loss of tracking.
  Walk(walk, half, [&](int64_t t) { return t < restart_ns ? t : t - restart_ns + 20'000'000; });
  // Tracked as before: the same places, and the flag as sure at the end. Not update for
  // update: the new clock's stamps sit on the timeline where the daemon's own clock put
  // them, so its 1-s updates fall a little apart from the clean walk's.
  ASSERT_EQ(link_->plan_poses.size(), clean.size());
  for (size_t k = half; k < clean.size(); ++k)
    EXPECT_LT(std::hypot(link_->plan_poses[k].x() - clean[k].x(),
                         link_->plan_poses[k].y() - clean[k].y()),
              0.1)
        << "pose " << k;
  EXPECT_EQ(link_->plan_poses.back().reliability().flag(), clean.back().reliability().flag());
  EXPECT_EQ(clean.back().reliability().flag(), v1::Reliability::RELIABLE);
  const std::string log = Log();
  const size_t restart_line = log.find("the clock started again");
  ASSERT_NE(restart_line, std::string::npos);
  EXPECT_NE(log.find("belief: ", restart_line), std::string::npos)
      << "no registration after the restart";
  EXPECT_TRUE(WaitForStatus(
      [](const v1::DaemonStatus& st) { return st.counters().clock_restarts() >= 1; }));
  EXPECT_EQ(link_->status->counters().clock_restarts(), 1u);
  // The poses after the restart carry the headset's new stamps.
  EXPECT_EQ(link_->plan_poses.back().source_stamp_ns(),
            walk.steps.back().stamp_ns - restart_ns + 20'000'000);
}

// 5. 200 malformed Commands gave 200 log lines.
TEST_F(HostileTest, AFloodOfMalformedCommandsLogsOnceASecond) {
  StartDaemon();
  tools::HeadsetLink& a = Attacker();
  platform::Writer raw(a.participant(), Topic::kCommand);
  for (int i = 0; i < 200; ++i) {
    platform::Envelope e;
    e.device_id = "hl-test";
    e.seq = raw.NextSeq();
    e.payload = "\xff\xff not a Command " + std::to_string(i);
    ASSERT_TRUE(raw.Write(e));
  }
  ASSERT_TRUE(WaitForStatus([](const v1::DaemonStatus& s) {
    return s.counters().commands_refused() >= 200;
  })) << link_->status->ShortDebugString();
  // A second later, one more: its line says how many were held back.
  link_->WaitUntil([] { return false; }, std::chrono::milliseconds(1100));
  platform::Envelope e;
  e.device_id = "hl-test";
  e.seq = raw.NextSeq();
  e.payload = "\xff";
  ASSERT_TRUE(raw.Write(e));
  ASSERT_TRUE(WaitForStatus(
      [](const v1::DaemonStatus& s) { return s.counters().commands_refused() >= 201; }));
  const std::string log = Log();
  size_t lines = 0;
  for (size_t at = log.find("command refused"); at != std::string::npos;
       at = log.find("command refused", at + 1))
    ++lines;
  std::printf("201 malformed commands: %zu log lines\n", lines);
  EXPECT_LE(lines, 3u) << log;
  EXPECT_NE(log.find("more like it in the last second"), std::string::npos) << log;
}

// 6. A 5-million-vertex mesh delta (60 MB) was dropped by DDS without a trace. Over
// loopback it arrives (and is refused, over the vertex limit); samples DDS rejects are
// made by a flood that outruns the daemon's mesh reader (1024 samples deep).
TEST_F(HostileTest, MeshesTooLargeOrTooManyLeaveACountAndALogLine) {
  StartDaemon();
  sim::SimMesh huge;
  huge.id = 77;
  huge.vertices_slam.resize(5'000'000);
  for (size_t i = 0; i < huge.vertices_slam.size(); ++i)
    huge.vertices_slam[i] = {static_cast<float>(i % 1000) * 0.01f,
                             static_cast<float>(i / 1000) * 0.01f, 1.0f};
  huge.triangles = {0, 1, 1000};
  tools::HeadsetLink& a = Attacker();
  a.Send(Topic::kMeshDelta, tools::ToMeshDelta(huge, kFrame, 1'000'000'000), 1'000'000'000);
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        if (!link_->status) return false;
        const auto& c = link_->status->counters();
        return c.over_limits() + c.samples_lost() + c.samples_rejected() > 0;
      },
      seconds(30)))
      << "no trace of the mesh: " << link_->status->ShortDebugString();
  // Then a flood faster than the daemon extracts walls: the mesh reader's queue (1024
  // samples) overflows; DDS rejects samples until there is room (and the writer resends).
  sim::SimMesh wall;
  for (int i = 0; i < 400; ++i)
    wall.vertices_slam.push_back(
        {static_cast<float>(i % 40) * 0.1f, 2.0f, static_cast<float>(i / 40) * 0.2f});
  for (uint32_t i = 0; i + 41 < 400; ++i) {
    wall.triangles.insert(wall.triangles.end(), {i, i + 1, i + 40, i + 1, i + 41, i + 40});
  }
  // In rounds of 3000 until the reader overflows: how fast the daemon drains it depends
  // on the machine's load, not on what is tested.
  bool rejected = false;
  for (int round = 0, n = 0; round < 10 && !rejected; ++round) {
    for (int i = 0; i < 3000; ++i, ++n) {
      wall.id = 1000 + static_cast<uint64_t>(n);
      a.Send(Topic::kMeshDelta, tools::ToMeshDelta(wall, kFrame, 2'000'000'000 + n),
             2'000'000'000 + n);
    }
    rejected = link_->WaitUntil(
        [&] { return link_->status && link_->status->counters().samples_rejected() > 0; },
        seconds(3));
  }
  ASSERT_TRUE(rejected) << link_->status->ShortDebugString();
  const auto& c = link_->status->counters();
  std::printf("60 MB mesh: over_limits %llu, samples_lost %llu, samples_rejected %llu\n",
              static_cast<unsigned long long>(c.over_limits()),
              static_cast<unsigned long long>(c.samples_lost()),
              static_cast<unsigned long long>(c.samples_rejected()));
  const std::string log = Log();
  EXPECT_TRUE(log.find("DDS lost") != std::string::npos ||
              log.find("rejected: mesh") != std::string::npos)
      << log;
}

// 7. A plan with coordinates of 1e300 was taken ("routes on a 1 x 1 grid of inf m"); a
// 440-byte plan whose walls lie 100 km apart took 553 MB when loaded at run time.
TEST_F(HostileTest, PlansOutOfBoundsAreRefusedAndLargeOnesStayWithinTheMemoryLimit) {
  StartDaemon("limits { max_plan_memory_mb: 64 }\n");
  auto write_plan = [&](const std::string& name, const std::string& coordinates) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << R"({"type": "FeatureCollection", "properties": {"units": "m"},
      "features": [{"type": "Feature", "properties": {"kind": "wall"}, "geometry":
      {"type": "LineString", "coordinates": )"
                        << coordinates << "}}]}";
    return path;
  };
  tools::HeadsetLink& a = Attacker();
  auto load = [&](const std::string& path) {
    v1::Command c;
    c.mutable_load_plan()->set_path(path);
    return a.Request(c, seconds(30));
  };
  for (const auto& [file, coordinates, reason] :
       {std::tuple{"huge.geojson", "[[0, 0], [1e300, 0]]", "beyond limits.max_plan_coordinate_m"},
        {"apart.geojson", "[[0, 0], [1, 0], [100000, 0], [100000, 1]]",
         "larger than limits.max_plan_extent_m"}}) {
    const auto refused = load(write_plan(file, coordinates));
    ASSERT_TRUE(refused) << file;
    EXPECT_FALSE(refused->ok()) << file;
    EXPECT_NE(refused->message().find(reason), std::string::npos) << refused->message();
  }
  // Within the limits but 1990 m across: the grids are made coarser to fit 64 MB.
  const auto wide =
      load(write_plan("wide.geojson", "[[0, 0], [1990, 0], [1990, 1990], [0, 1990], [0, 0]]"));
  ASSERT_TRUE(wide);
  EXPECT_TRUE(wide->ok()) << wide->message();
  const tools::ProcSample sample = tools::SampleProcess(daemon_->pid());
  std::printf("a 1990 m plan under max_plan_memory_mb 64: peak RSS %.0f MB\n", sample.hwm_mb);
  EXPECT_LT(sample.hwm_mb, 64.0 + 60.0);  // the grids, and the daemon without a plan (40 MB)
  EXPECT_NE(Log().find("times coarser than configured"), std::string::npos);
  // The daemon still answers.
  const sim::DemoWalk walk = DaemonTest::Walk(0.0, 1);
  link_->Send(Topic::kHeadsetPose, tools::ToHeadsetPose(walk.steps[0].slam, kFrame, 1), 1);
  EXPECT_TRUE(link_->WaitUntil([&] { return !link_->plan_poses.empty(); }, seconds(5)));
}

// 7, continued. A plan loaded at run time used to stall the poses while it was built.
TEST_F(HostileTest, APlanLoadedAtRunTimeIsBuiltWithoutHoldingUpThePoses) {
  StartDaemon();
  // A 240 x 170 m floor of 10 m rooms, built in a few hundred milliseconds.
  const std::string path = (dir_ / "mall.txt").string();
  {
    std::ofstream out(path);
    out << 25 + 18 << "\n";
    for (int i = 0; i <= 24; ++i) out << i * 10 << " 0 " << i * 10 << " 170\n";
    for (int j = 0; j <= 17; ++j) out << "0 " << j * 10 << " 240 " << j * 10 << "\n";
  }
  v1::Command load;
  load.set_request_id(77);
  load.mutable_load_plan()->set_path(path);
  link_->Send(Topic::kCommand, load, 0);
  const sim::DemoWalk walk = DaemonTest::Walk(0.0, 1);
  const size_t before = link_->plan_poses.size();
  size_t answered_while_loading = 0;
  int64_t stamp = 1'000'000'000;
  auto next_send = std::chrono::steady_clock::now();
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        for (const v1::CommandReply& r : link_->replies)
          if (r.request_id() == 77) return true;
        answered_while_loading = link_->plan_poses.size() - before;
        if (std::chrono::steady_clock::now() >= next_send) {  // a pose every 20 ms
          next_send += std::chrono::milliseconds(20);
          stamp += 20'000'000;
          link_->Send(Topic::kHeadsetPose, tools::ToHeadsetPose(walk.steps[0].slam, kFrame, stamp),
                      stamp);
        }
        return false;
      },
      seconds(30)));
  std::printf("plan poses answered while the plan was built: %zu\n", answered_while_loading);
  EXPECT_GT(answered_while_loading, 0u);
  for (const v1::CommandReply& r : link_->replies) {
    if (r.request_id() == 77) {
      EXPECT_TRUE(r.ok()) << r.message();
    }
  }
}

// 8. A second floorposed on the same state_dir used to start, and the two overwrote each
// other's snapshots.
TEST_F(HostileTest, ASecondDaemonOnTheSameStateDirectoryExitsWithTheReason) {
  const fs::path state = dir_ / "state";
  StartDaemon("state_dir: \"" + state.string() + "\"\n");
  const fs::path second_log = dir_ / "second.log";
  tools::ChildProcess second({FLOORPOSED_PATH, "--config", (dir_ / "floorposed.conf").string()},
                             second_log.string());
  ASSERT_TRUE(second.started());
  const std::optional<int> code = second.Wait(seconds(10));
  ASSERT_TRUE(code.has_value()) << "the second floorposed did not exit";
  EXPECT_NE(*code, 0);
  std::ifstream in(second_log);
  const std::string log{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  EXPECT_NE(log.find("state_dir " + state.string() + " is in use by another floorposed (pid " +
                     std::to_string(daemon_->pid()) + ")"),
            std::string::npos)
      << log;
  // The first one goes on.
  EXPECT_TRUE(daemon_->Running());
  link_->status.reset();
  EXPECT_TRUE(link_->WaitUntil([&] { return link_->status.has_value(); }, seconds(5)));
}

// 3. The snapshot reader trusted the file: a directory aborted floorposed, a FIFO hung it
// in open() (SIGTERM ignored), /dev/urandom or a sparse 600 MB file grew its memory.
class SnapshotPathTest : public HostileTest, public ::testing::WithParamInterface<std::string> {};

TEST_P(SnapshotPathTest, StartsCleanWithinTwoSecondsAndStopsOnSigterm) {
  const fs::path state = dir_ / "state";
  fs::create_directories(state);
  const std::string snapshot = platform::SnapshotPath(state.string(), "hl-test");
  const std::string kind = GetParam();
  if (kind == "directory") {
    fs::create_directories(fs::path(snapshot) / "inside");
  } else if (kind == "fifo") {
    ASSERT_EQ(::mkfifo(snapshot.c_str(), 0600), 0);
  } else if (kind == "urandom") {
    fs::create_symlink("/dev/urandom", snapshot);
  } else {
    std::ofstream(snapshot) << "FPSNAP1\n";
    fs::resize_file(snapshot, 600u << 20);  // sparse: a hole of 600 MB
  }
  WriteConfig("hl-test", "state_dir: \"" + state.string() + "\"\n", "floorposed.conf");
  const auto launched = std::chrono::steady_clock::now();
  LaunchDaemon();
  link_ =
      std::make_unique<tools::HeadsetLink>(domain_, platform::LoopbackCycloneConfig(), "hl-test");
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        return link_->status && link_->status->state() == v1::DaemonStatus::WAITING_FOR_ALIGNMENT;
      },
      seconds(10)))
      << "no clean start; log in " << dir_;
  const double up_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - launched).count();
  const tools::ProcSample sample = tools::SampleProcess(daemon_->pid());
  std::printf("%s: first status %.2f s after the start, RSS %.1f MB (peak %.1f MB)\n", kind.c_str(),
              up_s, sample.rss_mb, sample.hwm_mb);
  EXPECT_LT(up_s, 2.0);
  EXPECT_LT(sample.hwm_mb, 64.0);
  EXPECT_NE(Log().find("snapshot " + snapshot + " not trusted"), std::string::npos) << Log();
  EXPECT_FALSE(fs::exists(fs::symlink_status(snapshot))) << "not set aside";
  const auto stop = std::chrono::steady_clock::now();
  EXPECT_EQ(daemon_->Terminate(seconds(5)), 0);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - stop).count(), 2.0);
}

INSTANTIATE_TEST_SUITE_P(Kinds, SnapshotPathTest,
                         ::testing::Values("directory", "fifo", "urandom", "sparse600mb"));

}  // namespace
}  // namespace floorpose
