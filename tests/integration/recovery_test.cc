// Crash safety end to end (label recovery): a real floorposed killed with SIGKILL mid-walk
// resumes its alignment and wall store from the state snapshot; a corrupt or foreign
// snapshot is set aside with a log line and the daemon starts clean.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "platform/state_file.h"
#include "tests/integration/daemon_fixture.h"
#include "tools/lib/headset_messages.h"

namespace floorpose {
namespace {

using Clock = std::chrono::steady_clock;

class RecoveryTest : public DaemonTest {
 protected:
  void StartWithState() {
    state_dir_ = dir_ / "state";
    StartDaemon("state_dir: \"" + state_dir_.string() + "\"\nsnapshot_period_s: 0.5\n");
  }
  std::string snapshot_path() const {
    return platform::SnapshotPath(state_dir_.string(), "hl-test");
  }
  void SendStep(const sim::SimStep& step, bool meshes = true) {
    if (meshes)
      for (const sim::SimMesh& m : step.meshes)
        link_->Send(Topic::kMeshDelta, tools::ToMeshDelta(m, kFrame, step.stamp_ns), step.stamp_ns);
    link_->Send(Topic::kHeadsetPose, tools::ToHeadsetPose(step.slam, kFrame, step.stamp_ns),
                step.stamp_ns);
  }
  // The snapshot on disk, once it holds an alignment of at least this version.
  std::optional<v1::StateSnapshot> WaitForSnapshot(uint64_t version) {
    std::optional<v1::StateSnapshot> found;
    link_->WaitUntil(
        [&] {
          v1::StateSnapshot s;
          std::string error;
          if (platform::ReadStateFile(snapshot_path(), &s, &error) == platform::StateRead::kOk &&
              s.alignment().version() >= version)
            found = s;
          return found.has_value();
        },
        seconds(10));
    return found;
  }
  // A paced walk after a wall pick, then SIGTERM (which writes the last snapshot).
  void WalkAndStop(const sim::DemoWalk& walk) {
    ASSERT_NO_FATAL_FAILURE(PickAndWalk(walk));
    ASSERT_EQ(daemon_->Terminate(seconds(5)), 0);
  }
  // Restarts floorposed and waits for its first status.
  void Restart() {
    link_->status.reset();
    LaunchDaemon();
    ASSERT_TRUE(link_->WaitUntil([&] { return link_->status.has_value(); }, seconds(15)))
        << "floorposed did not come back; log in " << dir_;
  }

  fs::path state_dir_;
};

TEST_F(RecoveryTest, KilledMidWalkResumesTheAlignmentWithinTwoSeconds) {
  StartWithState();
  const sim::DemoWalk walk = Walk(/*pick_error_m=*/0.3, 3);
  link_->Send(Topic::kCommand, tools::ToWallPickCommand(walk, kFrame, 1), 0);
  ASSERT_TRUE(link_->WaitUntil([&] { return !link_->alignments.empty(); }, seconds(10)));
  const size_t half = walk.steps.size() * 2 / 3;
  for (size_t k = 0; k < half; ++k) {
    SendStep(walk.steps[k]);
    link_->WaitUntil([] { return false; }, std::chrono::milliseconds(15));
  }
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        return link_->plan_poses.size() == half && link_->status &&
               link_->status->counters().registrations_accepted() >= 1;
      },
      seconds(10)))
      << "status: " << (link_->status ? link_->status->ShortDebugString() : "none");
  // The alignment in use once the last registration is in, and the snapshot that has it.
  link_->WaitUntil([] { return false; }, std::chrono::milliseconds(500));
  const v1::Alignment before = link_->alignments.back();
  ASSERT_EQ(before.source(), v1::Alignment::REGISTRATION);
  const std::optional<v1::StateSnapshot> saved = WaitForSnapshot(before.version());
  ASSERT_TRUE(saved) << "no snapshot with alignment version " << before.version();
  ASSERT_EQ(saved->alignment().version(), before.version());
  ASSERT_GT(saved->meshes_size(), 0);

  daemon_->Kill();
  const size_t poses_before = link_->plan_poses.size();
  const auto restarted = Clock::now();
  LaunchDaemon();
  // The next pose of the walk, sent until the new daemon answers it.
  const sim::SimStep& next = walk.steps[half];
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        SendStep(next, /*meshes=*/false);
        return link_->plan_poses.size() > poses_before;
      },
      seconds(10)))
      << "no plan pose after the restart; log in " << dir_;
  const double answered_s = std::chrono::duration<double>(Clock::now() - restarted).count();
  const v1::PlanPose& first = link_->plan_poses[poses_before];
  EXPECT_LT(answered_s, 2.0) << "first plan pose " << answered_s << " s after the restart";
  std::printf("first plan pose %.2f s after the restart (alignment version %llu, %d meshes)\n",
              answered_s, static_cast<unsigned long long>(before.version()), saved->meshes_size());
  EXPECT_EQ(first.alignment_version(), before.version());
  const v1::Se2& t = before.t_plan_slam();
  const Pose2 expected = Apply(Se2{t.theta(), {t.x(), t.y()}}, next.slam);
  EXPECT_NEAR(first.x(), expected.position.x(), 1e-6);
  EXPECT_NEAR(first.y(), expected.position.y(), 1e-6);
  EXPECT_NE(first.reliability().flag(), v1::Reliability::UNRELIABLE)
      << first.reliability().reason();
  EXPECT_NE(Log().find("resumed from " + snapshot_path()), std::string::npos);

  // The rest of the walk, with the walls seen before the crash: it stays registered.
  for (size_t k = half + 1; k < walk.steps.size(); ++k) {
    SendStep(walk.steps[k]);
    link_->WaitUntil([] { return false; }, std::chrono::milliseconds(15));
  }
  ASSERT_TRUE(link_->WaitUntil(
      [&] { return link_->plan_poses.back().source_stamp_ns() == walk.steps.back().stamp_ns; },
      seconds(10)));
  const Pose2& truth = walk.steps.back().true_plan;
  const v1::PlanPose& last = link_->plan_poses.back();
  EXPECT_LT(std::hypot(last.x() - truth.position.x(), last.y() - truth.position.y()), 0.1);
}

TEST_F(RecoveryTest, ACorruptSnapshotIsSetAsideAndTheDaemonStartsClean) {
  StartWithState();
  ASSERT_NO_FATAL_FAILURE(WalkAndStop(Walk(/*pick_error_m=*/0.0, 1)));
  ASSERT_TRUE(WaitForSnapshot(1));
  // One bit flipped in the middle of the payload.
  {
    std::fstream f(snapshot_path(), std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(0, std::ios::end);
    const auto size = static_cast<std::streamoff>(f.tellg());
    ASSERT_GT(size, 64);
    f.seekg(size / 2);
    char c = 0;
    f.get(c);
    f.seekp(size / 2);
    f.put(static_cast<char>(c ^ 0x10));
  }
  Restart();
  ASSERT_TRUE(WaitForStatus([](const v1::DaemonStatus& s) {
    return s.state() == v1::DaemonStatus::WAITING_FOR_ALIGNMENT && s.live_meshes() == 0;
  })) << "status: "
      << link_->status->ShortDebugString();
  const std::string log = Log();
  EXPECT_NE(log.find("snapshot " + snapshot_path() + " not trusted: checksum mismatch"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("set aside as " + snapshot_path() + ".bad-"), std::string::npos);
  size_t aside = 0;
  for (const auto& entry : fs::directory_iterator(state_dir_))
    aside += entry.path().filename().string().rfind("hl-test.snapshot.bad-", 0) == 0;
  EXPECT_EQ(aside, 1u);
}

TEST_F(RecoveryTest, ASnapshotOfAChangedPlanIsNotTrusted) {
  StartWithState();
  ASSERT_NO_FATAL_FAILURE(WalkAndStop(Walk(/*pick_error_m=*/0.0, 1)));
  ASSERT_TRUE(WaitForSnapshot(1));
  // Someone moved the inner wall in the plan file meanwhile.
  std::string plan = kRoomGeoJson;
  const std::string inner = "[[4, 0], [4, 3.5]]";
  ASSERT_NE(plan.find(inner), std::string::npos);
  plan.replace(plan.find(inner), inner.size(), "[[4.5, 0], [4.5, 3.5]]");
  std::ofstream(plan_path_) << plan;
  Restart();
  ASSERT_TRUE(WaitForStatus([](const v1::DaemonStatus& s) {
    return s.state() == v1::DaemonStatus::WAITING_FOR_ALIGNMENT && s.live_meshes() == 0;
  })) << "status: "
      << link_->status->ShortDebugString();
  EXPECT_NE(Log().find("as it was before it changed"), std::string::npos);
}

}  // namespace
}  // namespace floorpose
