// floorposed end to end: a real daemon process on a private loopback DDS domain, driven
// by a real Cyclone participant in the test, as the HoloLens app would.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <thread>

#include "core/sim/demo_walk.h"
#include "core/wall_extractor.h"
#include "daemon/scheduling.h"
#include "floorpose/v1/config.pb.h"
#include "platform/config.h"
#include "platform/dds.h"
#include "platform/floor_plan_io.h"
#include "tests/daemon_test_util.h"
#include "tests/integration/daemon_fixture.h"
#include "tools/lib/headset_link.h"
#include "tools/lib/headset_messages.h"
#include "tools/lib/process.h"

namespace floorpose {
namespace {

TEST_F(DaemonTest, EveryPoseGivesAPlanPoseAndThePickSetsTheTransform) {
  StartDaemon();
  const sim::DemoWalk walk = Walk(/*pick_error_m=*/0.0, 1);
  ASSERT_GE(walk.steps.size(), 30u);
  ASSERT_TRUE(WaitForStatus([](const v1::DaemonStatus& s) {
    return s.state() == v1::DaemonStatus::WAITING_FOR_ALIGNMENT;
  }));

  // Before the pick: plan poses still come, flagged unreliable with version 0.
  const size_t before = 10;
  for (size_t k = 0; k < before; ++k) {
    const v1::HeadsetPose pose =
        tools::ToHeadsetPose(walk.steps[k].slam, kFrame, walk.steps[k].stamp_ns);
    if (k == 0)
      ASSERT_TRUE(link_->SendPoseAndAwaitAnswer(pose, 0, seconds(10)))
          << "no answer to the first pose";
    else
      link_->Send(Topic::kHeadsetPose, pose, 0);
  }
  ASSERT_TRUE(link_->WaitUntil([&] { return link_->plan_poses.size() == before; }, seconds(10)));
  for (const v1::PlanPose& p : link_->plan_poses) {
    EXPECT_EQ(p.alignment_version(), 0u);
    EXPECT_EQ(p.reliability().flag(), v1::Reliability::UNRELIABLE);
  }

  link_->Send(Topic::kCommand, tools::ToWallPickCommand(walk, kFrame, 7), 0);
  ASSERT_TRUE(link_->WaitUntil([&] { return !link_->alignments.empty(); }, seconds(10)));
  EXPECT_EQ(link_->alignments.back().source(), v1::Alignment::WALL_PICK);
  // Equation 6.2 with an exact pick recovers the true T_plan_slam = T_slam_plan^-1.
  const Se2 truth = walk.T_slam_plan_initial.Inverse();
  EXPECT_NEAR(link_->alignments.back().t_plan_slam().theta(), truth.theta, 1e-9);
  EXPECT_NEAR(link_->alignments.back().t_plan_slam().x(), truth.t.x(), 1e-6);
  EXPECT_NEAR(link_->alignments.back().t_plan_slam().y(), truth.t.y(), 1e-6);

  // After the pick, poses only (no meshes, so no registration): each is the truth.
  for (size_t k = before; k < walk.steps.size(); ++k)
    link_->Send(Topic::kHeadsetPose,
                tools::ToHeadsetPose(walk.steps[k].slam, kFrame, walk.steps[k].stamp_ns), 0);
  ASSERT_TRUE(
      link_->WaitUntil([&] { return link_->plan_poses.size() == walk.steps.size(); }, seconds(10)))
      << link_->plan_poses.size() << " of " << walk.steps.size();
  for (size_t k = before; k < walk.steps.size(); ++k) {
    const v1::PlanPose& p = link_->plan_poses[k];
    const sim::SimStep& step = walk.steps[k];
    ASSERT_EQ(p.source_stamp_ns(), step.stamp_ns);
    EXPECT_NEAR(p.x(), step.true_plan.position.x(), 1e-5) << "pose " << k;
    EXPECT_NEAR(p.y(), step.true_plan.position.y(), 1e-5) << "pose " << k;
    EXPECT_NEAR(WrapAngle(p.heading() - step.true_plan.heading), 0.0, 1e-6) << "pose " << k;
    EXPECT_GE(p.alignment_version(), 1u);
  }
}

// How the kernel schedules each of floorposed's threads, by name: the nice value (field
// 19 of /proc/PID/task/TID/stat) and, where the kernel shows it (EEVDF, Linux 6.6 and
// later), the slice it grants (se.slice in /proc/PID/task/TID/sched, nanoseconds).
struct ThreadSchedule {
  int nice = 0;
  std::optional<long> slice_ns;
};

std::map<std::string, ThreadSchedule> ThreadSchedules(pid_t pid) {
  std::map<std::string, ThreadSchedule> threads;
  const fs::path tasks = fs::path("/proc") / std::to_string(pid) / "task";
  for (const auto& task : fs::directory_iterator(tasks)) {
    const std::vector<std::string> stat = tools::ProcStatFields((task.path() / "stat").string());
    if (stat.size() < 19) continue;
    ThreadSchedule& t = threads[stat[1]];
    t.nice = std::stoi(stat[18]);
    std::ifstream sched(task.path() / "sched");
    for (std::string line; std::getline(sched, line);)
      if (line.rfind("se.slice", 0) == 0) t.slice_ns = std::stol(line.substr(line.find(':') + 1));
  }
  return threads;
}

TEST_F(DaemonTest, TheRegistrationWorkerYieldsToThePoses) {
  // The worker runs at nice 10 with the kernel's default slice; every other thread (the io
  // thread, DDS's) at the daemon's own priority, asking for the shortest slice.
  StartDaemon();
  std::map<std::string, ThreadSchedule> threads;  // the threads name themselves as they start
  for (int i = 0; i < 100 && !(threads.count("fp-worker") && threads.count("fp-io")); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    threads = ThreadSchedules(daemon_->pid());
  }
  std::string names;
  for (const auto& [name, t] : threads) names += name + " ";
  ASSERT_TRUE(threads.count("fp-worker")) << "threads: " << names;
  ASSERT_TRUE(threads.count("fp-io")) << "threads: " << names;
  const ThreadSchedule worker = threads.at("fp-worker");
  EXPECT_EQ(worker.nice, kBackgroundNice);
  EXPECT_LT(threads.at("fp-io").nice, kBackgroundNice);
  EXPECT_EQ(Log().find("keeps its priority"), std::string::npos) << Log();
  EXPECT_EQ(Log().find("default turns"), std::string::npos) << Log();
  if (!worker.slice_ns) GTEST_SKIP() << "this kernel shows no se.slice (EEVDF is Linux 6.6+)";
  for (const auto& [name, t] : threads) {
    if (name == "fp-worker") continue;
    EXPECT_EQ(t.slice_ns, kShortSliceNs) << name;
  }
  EXPECT_GT(*worker.slice_ns, kShortSliceNs);
}

TEST_F(DaemonTest, AddedUpdatedAndRemovedDeltasChangeTheStore) {
  StartDaemon();
  // Expected point counts come from the same extraction the daemon runs (default config).
  v1::FloorposedConfig defaults;
  const WallExtractionOptions wall_options = platform::ToWallExtractionOptions(defaults);
  auto count = [&](const sim::SimMesh& m) {
    return ExtractWallPoints({&m.vertices_slam, &m.triangles}, m.id, wall_options).size();
  };
  auto wall = [](uint64_t id, sim::MeshChange change, float x0, float x1) {
    sim::SimMesh m;
    m.id = id;
    m.change = change;
    m.vertices_slam = {{x0, 0, 0},  {x1, 0, 0}, {x1, 0, 2.5f}, {x0, 0, 2.5f},
                       {x0, -1, 0}, {x1, -1, 0}};  // the last two make a floor triangle
    m.triangles = {0, 1, 2, 0, 2, 3, 0, 1, 5};
    return m;
  };
  const sim::SimMesh a = wall(1, sim::MeshChange::kAdded, 0, 4);
  const sim::SimMesh b = wall(2, sim::MeshChange::kAdded, 5, 6);
  const sim::SimMesh a2 = wall(1, sim::MeshChange::kUpdated, 0, 2);
  ASSERT_GT(count(a), count(a2));

  link_->Send(Topic::kMeshDelta, tools::ToMeshDelta(a, kFrame, 1), 1);
  link_->Send(Topic::kMeshDelta, tools::ToMeshDelta(b, kFrame, 2), 2);
  ASSERT_TRUE(WaitForStatus([&](const v1::DaemonStatus& s) {
    return s.live_meshes() == 2 && s.wall_points() == count(a) + count(b);
  })) << "status: "
      << link_->status->ShortDebugString();

  link_->Send(Topic::kMeshDelta, tools::ToMeshDelta(a2, kFrame, 3), 3);
  ASSERT_TRUE(WaitForStatus([&](const v1::DaemonStatus& s) {
    return s.live_meshes() == 2 && s.wall_points() == count(a2) + count(b) &&
           s.counters().meshes_updated() == 1;
  })) << "status: "
      << link_->status->ShortDebugString();

  sim::SimMesh remove_b;
  remove_b.id = 2;
  remove_b.change = sim::MeshChange::kRemoved;
  link_->Send(Topic::kMeshDelta, tools::ToMeshDelta(remove_b, kFrame, 4), 4);
  ASSERT_TRUE(WaitForStatus([&](const v1::DaemonStatus& s) {
    return s.live_meshes() == 1 && s.wall_points() == count(a2) &&
           s.counters().meshes_removed() == 1;
  })) << "status: "
      << link_->status->ShortDebugString();

  // Bad input: a REMOVED for an unknown id and garbage bytes are counted, not fatal, and
  // the store keeps what it had.
  remove_b.id = 99;
  link_->Send(Topic::kMeshDelta, tools::ToMeshDelta(remove_b, kFrame, 5), 5);
  platform::Writer raw(link_->participant(), Topic::kMeshDelta);
  ASSERT_TRUE(link_->WaitUntil([&] { return raw.MatchedReaders() > 0; }, seconds(10)));
  raw.Write({"hl-test", 1, 6, std::string("\xff\xff\xff\xff not protobuf", 17)});
  ASSERT_TRUE(WaitForStatus([&](const v1::DaemonStatus& s) {
    return s.counters().unknown_mesh_ids() == 1 && s.counters().rejected_messages() == 1 &&
           s.live_meshes() == 1 && s.wall_points() == count(a2);
  })) << "status: "
      << link_->status->ShortDebugString();
  EXPECT_TRUE(daemon_->Running());
}

TEST_F(DaemonTest, RegistrationCorrectsAnImpreciseWallPick) {
  // Updates and the search that checks the pick run as `floorpose eval` runs them: under
  // wall-clock scheduling on a loaded machine the walk could end before the check did,
  // and the last pose stay DEGRADED ("not yet checked").
  StartDaemon("deterministic: true\n");
  const sim::DemoWalk walk = Walk(/*pick_error_m=*/0.3, 3);
  ASSERT_TRUE(WaitForStatus([](const v1::DaemonStatus& s) {
    return s.state() == v1::DaemonStatus::WAITING_FOR_ALIGNMENT;
  }));
  ASSERT_NO_FATAL_FAILURE(PickAndWalk(walk));
  ASSERT_TRUE(WaitForStatus([](const v1::DaemonStatus& s) {
    return s.counters().registrations_accepted() >= 1;
  })) << "status: "
      << link_->status->ShortDebugString();
  // The pick alone puts the wearer off by more than 5 cm; the registered last pose is not.
  const v1::Se2& pick = link_->alignments.front().t_plan_slam();
  const Pose2 picked = Apply(Se2{pick.theta(), {pick.x(), pick.y()}}, walk.steps.back().slam);
  const Pose2& truth = walk.steps.back().true_plan;
  EXPECT_GT((picked.position - truth.position).norm(), 0.05);
  const v1::PlanPose& last = link_->plan_poses.back();
  EXPECT_LT(std::hypot(last.x() - truth.position.x(), last.y() - truth.position.y()), 0.05);
  EXPECT_EQ(link_->plan_poses.back().reliability().flag(), v1::Reliability::RELIABLE);
}

TEST_F(DaemonTest, RefusesBadCommandsWithACorrelatedReason) {
  StartDaemon();
  v1::Command flip;
  flip.mutable_flip();
  const auto flipped = link_->Request(flip, seconds(5));
  ASSERT_TRUE(flipped.has_value());
  EXPECT_FALSE(flipped->ok());
  EXPECT_EQ(flipped->command(), "flip");
  EXPECT_EQ(flipped->message(), "no alignment to flip");
  v1::Command load;
  load.mutable_load_plan()->set_path((dir_ / "missing.geojson").string());
  const auto loaded = link_->Request(load, seconds(5));
  ASSERT_TRUE(loaded.has_value());
  EXPECT_FALSE(loaded->ok());
  EXPECT_NE(loaded->message().find("missing.geojson"), std::string::npos) << loaded->message();
  // The plan it had is still loaded, and the reply says so.
  EXPECT_EQ(loaded->status().state(), v1::DaemonStatus::WAITING_FOR_ALIGNMENT);
  EXPECT_EQ(loaded->status().plan_id(), "room");
  EXPECT_EQ(loaded->status().counters().commands_refused(), 2u);
  // The status topic tells dashboards the same, prefixed with the request id.
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        return std::count(link_->status_messages.begin(), link_->status_messages.end(),
                          "request " + std::to_string(loaded->request_id()) +
                              ": refused: " + loaded->message()) == 1;
      },
      seconds(5)));
  // A payload that is not a Command is refused with request id 0, not dropped silently.
  platform::Participant& p = link_->participant();
  platform::Writer raw(p, Topic::kCommand);
  ASSERT_TRUE(link_->WaitUntil([&] { return raw.MatchedReaders() > 0; }, seconds(5)));
  ASSERT_TRUE(raw.Write({"hl-test", 1, 0, "\xff\xff\xff"}));
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        return std::any_of(link_->replies.begin(), link_->replies.end(), [](const auto& r) {
          return r.request_id() == 0 && !r.ok() && r.message() == "malformed Command protobuf";
        });
      },
      seconds(5)));
}

TEST_F(DaemonTest, LoadsPlansByIdFromItsPlanDirectory) {
  const fs::path plans = dir_ / "plans";
  fs::create_directories(plans);
  fs::copy_file(plan_path_, plans / "annex.geojson");
  fs::copy_file(FLOORPOSE_DEMO_PLAN, plans / "office.geojson");
  std::ofstream(plans / "notes.md") << "not a plan";
  StartDaemon("plan_dir: \"" + plans.string() + "\"\n");

  v1::Command get_state;
  get_state.mutable_get_state();
  const auto state = link_->Request(get_state, seconds(5));
  ASSERT_TRUE(state.has_value());
  EXPECT_TRUE(state->ok());
  EXPECT_EQ(state->command(), "get_state");
  EXPECT_EQ(std::vector<std::string>(state->plans().begin(), state->plans().end()),
            (std::vector<std::string>{"annex", "office"}));
  EXPECT_EQ(state->status().plan_id(), "room");
  EXPECT_EQ(state->status().state(), v1::DaemonStatus::WAITING_FOR_ALIGNMENT);

  v1::Command load;
  load.mutable_load_plan()->set_plan_id("office");
  load.mutable_load_plan()->set_floor("2");
  const auto loaded = link_->Request(load, seconds(5));
  ASSERT_TRUE(loaded.has_value());
  EXPECT_TRUE(loaded->ok()) << loaded->message();
  EXPECT_EQ(loaded->status().plan_id(), "office");

  // Ids are names in the directory, never paths out of it.
  for (const char* bad : {"../room", "/etc/passwd", ".hidden", "no-such-plan", ""}) {
    v1::Command c;
    c.mutable_load_plan()->set_plan_id(bad);
    const auto reply = link_->Request(c, seconds(5));
    ASSERT_TRUE(reply.has_value()) << bad;
    EXPECT_FALSE(reply->ok()) << bad;
    EXPECT_FALSE(reply->message().empty());
    EXPECT_EQ(reply->status().plan_id(), "office") << bad;
  }
  v1::Command both;
  both.mutable_load_plan()->set_plan_id("annex");
  both.mutable_load_plan()->set_path(plan_path_);
  const auto refused = link_->Request(both, seconds(5));
  ASSERT_TRUE(refused.has_value());
  EXPECT_EQ(refused->message(), "give plan_id or path, not both");
}

TEST(FloorposedProcess, PrintConfigRoundTrips) {
  const fs::path out =
      fs::path(::testing::TempDir()) / ("print-config-" + std::to_string(getpid()));
  tools::ChildProcess p({FLOORPOSED_PATH, "--print-config"}, out.string());
  // It exits on its own; Terminate only waits (SIGTERM to an exited process is harmless).
  for (int i = 0; i < 200 && p.Running(); ++i) usleep(10000);
  ASSERT_EQ(p.Terminate(seconds(2)), 0);
  std::ifstream in(out);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  v1::FloorposedConfig parsed;
  std::string error;
  ASSERT_TRUE(platform::ParseConfig(text, &parsed, &error)) << error;
  EXPECT_EQ(parsed.walls().density_per_m2(), 50.0);
  EXPECT_EQ(platform::ResolvedConfigText(parsed), text);
}

}  // namespace
}  // namespace floorpose

namespace floorpose {
namespace {

TEST_F(DaemonTest, AnswersRoutesAndPublishesWhatWasExplored) {
  // Deterministic: the walk, sent at 20 times its pace, ends RELIABLE however loaded the
  // machine is (the belief's updates are applied before the next pose).
  StartDaemon("deterministic: true\nexplored { publish_period_s: 2 }\n");
  const sim::DemoWalk walk = Walk(/*pick_error_m=*/0.0, 5);
  v1::Command route;
  route.mutable_route()->set_to_x(8.0);
  route.mutable_route()->set_to_y(4.0);
  // Before the wearer is on the plan: a clear refusal.
  const auto early = link_->Request(route, seconds(5));
  ASSERT_TRUE(early.has_value());
  EXPECT_FALSE(early->ok());
  EXPECT_EQ(early->command(), "route");
  EXPECT_NE(early->message().find("no position on the plan"), std::string::npos)
      << early->message();

  ASSERT_NO_FATAL_FAILURE(PickAndWalk(walk));
  const v1::PlanPose last = link_->plan_poses.back();
  ASSERT_EQ(last.reliability().flag(), v1::Reliability::RELIABLE) << last.ShortDebugString();

  const auto answer = link_->Request(route, seconds(5));
  ASSERT_TRUE(answer.has_value());
  ASSERT_TRUE(answer->ok()) << answer->message();
  const v1::RouteReply& r = answer->route();
  ASSERT_GE(r.path_size(), 2);
  EXPECT_NEAR(r.path(0).x(), last.x(), 1e-9);
  EXPECT_NEAR(r.path(0).y(), last.y(), 1e-9);
  EXPECT_NEAR(r.path(r.path_size() - 1).x(), 8.0, 1e-9);
  EXPECT_NEAR(r.path(r.path_size() - 1).y(), 4.0, 1e-9);
  EXPECT_GE(r.length_m(), std::hypot(8.0 - last.x(), 4.0 - last.y()) - 1e-9);
  EXPECT_EQ(r.from_reliability().flag(), last.reliability().flag());

  // Outside the plan: refused, and the daemon carries on.
  v1::Command away = route;
  away.mutable_route()->set_to_x(500.0);
  const auto refused = link_->Request(away, seconds(5));
  ASSERT_TRUE(refused.has_value());
  EXPECT_FALSE(refused->ok());
  EXPECT_NE(refused->message().find("outside the plan"), std::string::npos) << refused->message();
  EXPECT_FALSE(refused->has_route());

  // The explored map: the room the walk was in, and walls and free space seen.
  ASSERT_TRUE(link_->WaitUntil(
      [&] { return link_->explored && link_->explored->visited_size() > 0; }, seconds(10)))
      << (link_->explored ? link_->explored->ShortDebugString().substr(0, 300) : "none") << " last "
      << link_->plan_poses.back().ShortDebugString();
  const v1::ExploredMap& e = *link_->explored;
  EXPECT_EQ(e.rooms(), 1u);
  EXPECT_EQ(e.visited(0).id(), 0u);
  EXPECT_GT(e.free_cells(), 100u);
  EXPECT_GT(e.wall_cells(), 10u);
  EXPECT_GT(e.width() * e.height(), e.free_cells());
  EXPECT_TRUE(daemon_->Running());
}

}  // namespace
}  // namespace floorpose
