// DDS Security end to end (label security): floorposed with Cyclone's authentication,
// access control and encryption, identities made by tools/make-dds-security.sh. A
// participant without a valid identity (none at all, or one from another CA under the
// same name) can neither feed the daemon nor read it; a permitted one can.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <thread>

#include "tests/integration/daemon_fixture.h"
#include "tools/lib/dashboard.h"
#include "tools/lib/headset_messages.h"
// clang-format off
#include <httplib.h>  // after Eigen: glibc's <resolv.h> defines _res, a name in Eigen
#include <nlohmann/json.hpp>
// clang-format on

namespace floorpose {
namespace {

class SecurityTest : public DaemonTest {
 protected:
  void SetUp() override {
    DaemonTest::SetUp();
    // Ours, and a rogue CA that issues an "app" identity of its own.
    for (const auto& [dir, names] :
         {std::pair{"pki", "floorposed app:headset:hl-test intruder:headset:hl-other dashboard"},
          {"rogue", "app:headset:hl-test"}}) {
      const std::string cmd = std::string(FLOORPOSE_SOURCE_DIR) + "/tools/make-dds-security.sh '" +
                              (dir_ / dir).string() + "' " + names + " > '" +
                              (dir_ / dir).string() + ".log' 2>&1";
      ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd << " failed; see " << dir_;
    }
  }
  platform::DdsSecurity Identity(const std::string& dir, const std::string& name) const {
    return platform::SecurityFilesIn((dir_ / dir).string(), name);
  }
  std::string SecurityConfig(const platform::DdsSecurity& s) const {
    return "security { identity_ca: '" + s.identity_ca + "' identity_certificate: '" +
           s.identity_certificate + "' private_key: '" + s.private_key + "' permissions_ca: '" +
           s.permissions_ca + "' governance: '" + s.governance + "' permissions: '" +
           s.permissions + "' }";
  }
  // Sends a wall pick and the walk's poses on `link`, paced so that the daemon's keep-last
  // reader never has to drop one on a loaded machine (the first before the rest:
  // HeadsetLink::SendPoseAndAwaitAnswer).
  static void Drive(tools::HeadsetLink& link, const sim::DemoWalk& walk, int64_t stamp_offset) {
    link.Send(Topic::kCommand, tools::ToWallPickCommand(walk, kFrame, 1), 0);
    for (const sim::SimStep& step : walk.steps) {
      const int64_t stamp = step.stamp_ns + stamp_offset;
      const v1::HeadsetPose pose = tools::ToHeadsetPose(step.slam, kFrame, stamp);
      if (&step == &walk.steps.front())
        ASSERT_TRUE(link.SendPoseAndAwaitAnswer(pose, stamp, seconds(10)))
            << "no answer to the first pose";
      else
        link.Send(Topic::kHeadsetPose, pose, stamp);
      link.WaitUntil([] { return false; }, std::chrono::milliseconds(5));
    }
  }
};

TEST_F(SecurityTest, OnlyAPermittedParticipantFeedsAndReadsTheDaemon) {
  const platform::DdsSecurity app = Identity("pki", "app");
  dds_extra_ = SecurityConfig(Identity("pki", "floorposed"));
  StartDaemon("", &app);
  ASSERT_TRUE(WaitForStatus([](const v1::DaemonStatus& s) {
    return s.state() == v1::DaemonStatus::WAITING_FOR_ALIGNMENT;
  }));

  // Peers, each a process of its own sending a wall mesh, a pose and a get_state command
  // five times a second for 4 s: no identity at all, an "app" identity of another CA,
  // and, as the control, our app's identity. The in-process app sends nothing meanwhile.
  auto run_peer = [&](const std::string& name, std::vector<std::string> identity) {
    std::vector<std::string> argv = {DDS_PEER_PATH, std::to_string(domain_), "hl-test", "4"};
    argv.insert(argv.end(), identity.begin(), identity.end());
    const fs::path out = dir_ / (name + ".out");
    tools::ChildProcess process(argv, out.string());
    EXPECT_EQ(process.Wait(seconds(30)), 0) << name << ": see " << out;
    std::ifstream in(out);
    std::string line, heard;
    while (std::getline(in, line))
      if (line.rfind("plan_poses ", 0) == 0) heard = line;
    return heard;
  };
  auto counters = [&] {
    link_->WaitUntil([] { return false; }, seconds(1));  // a fresh status
    return link_->status->counters();
  };
  EXPECT_EQ(run_peer("open", {}), "plan_poses 0 status 0 replies 0");
  EXPECT_EQ(run_peer("impostor", {(dir_ / "rogue").string(), "app"}),
            "plan_poses 0 status 0 replies 0");
  // The daemon took nothing of theirs.
  v1::DaemonStatus::Counters c = counters();
  EXPECT_EQ(c.mesh_deltas_in(), 0u) << c.ShortDebugString();
  EXPECT_EQ(c.poses_in(), 0u) << c.ShortDebugString();
  EXPECT_EQ(c.commands_in(), 0u) << c.ShortDebugString();

  // The permitted peer is fed and answered in the same 4 s.
  const std::string permitted = run_peer("permitted", {(dir_ / "pki").string(), "app"});
  size_t plan_poses = 0, replies = 0;
  int status = 0;
  ASSERT_EQ(std::sscanf(permitted.c_str(), "plan_poses %zu status %d replies %zu", &plan_poses,
                        &status, &replies),
            3)
      << permitted;
  EXPECT_GT(plan_poses, 0u);
  EXPECT_EQ(status, 1);
  EXPECT_GT(replies, 0u);
  c = counters();
  EXPECT_GE(c.poses_in(), plan_poses) << c.ShortDebugString();
  EXPECT_GT(c.mesh_deltas_in(), 0u) << c.ShortDebugString();
  EXPECT_GT(c.commands_in(), 0u) << c.ShortDebugString();

  // A headset identity of another device cannot feed this one's daemon: neither in this
  // device's partition nor in the default one.
  for (const std::string partition : {"device/hl-test", "-"}) {
    const fs::path out = dir_ / ("intruder" + std::to_string(partition.size()) + ".out");
    tools::ChildProcess process({DDS_PEER_PATH, "--feed", partition, std::to_string(domain_),
                                 "hl-test", (dir_ / "pki").string(), "intruder"},
                                out.string());
    EXPECT_EQ(process.Wait(seconds(30)), 0) << "see " << out;
    std::ifstream in(out);
    const std::string said{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    std::printf("intruder in partition %s: %s", partition.c_str(), said.c_str());
    EXPECT_NE(said.find("refused"), std::string::npos) << said;
  }
  EXPECT_EQ(counters().poses_in(), c.poses_in()) << "the intruder's poses reached the daemon";

  // The app in this process, permitted too: a walk after a pick comes back on the plan.
  const sim::DemoWalk walk = Walk(/*pick_error_m=*/0.0, 1);
  const size_t before = link_->plan_poses.size();
  Drive(*link_, walk, 0);
  ASSERT_TRUE(link_->WaitUntil(
      [&] { return link_->plan_poses.size() == before + walk.steps.size(); }, seconds(10)))
      << link_->plan_poses.size() - before << " of " << walk.steps.size() << "; log in " << dir_;
  const Pose2& truth = walk.steps.back().true_plan;
  EXPECT_NEAR(link_->plan_poses.back().x(), truth.position.x(), 1e-5);
  EXPECT_NEAR(link_->plan_poses.back().y(), truth.position.y(), 1e-5);
}

// Roles (tools/make-dds-security.sh): only a daemon's identity may publish plan poses. Any
// permitted identity used to be able to forge them: the app published x = 999, RELIABLE,
// for another device, and a reader took all 20.
TEST_F(SecurityTest, OnlyADaemonIdentityGetsAPlanPoseToAReader) {
  // The reader: a dashboard, in this process.
  const platform::DdsSecurity dashboard = Identity("pki", "dashboard");
  platform::Participant participant(domain_, platform::LoopbackCycloneConfig(), &dashboard);
  platform::Reader reader(participant, Topic::kPlanPose);
  auto forge = [&](const std::string& name) {
    const fs::path out = dir_ / ("forge-" + name + ".out");
    tools::ChildProcess process({DDS_PEER_PATH, "--forge", std::to_string(domain_), "hl-victim",
                                 (dir_ / "pki").string(), name},
                                out.string());
    EXPECT_EQ(process.Wait(seconds(30)), 0) << name << ": see " << out;
    std::ifstream in(out);
    std::string line, said;
    while (std::getline(in, line))
      if (line.rfind("forged ", 0) == 0 || line.rfind("refused ", 0) == 0) said = line;
    // What reached the reader (keep-last 1 per device: one sample stands for them all).
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    size_t received = 0;
    for (const platform::Envelope& e : reader.Take(100)) received += e.device_id == "hl-victim";
    std::printf("%s: %s; the dashboard received %zu\n", name.c_str(), said.c_str(), received);
    return received;
  };
  EXPECT_EQ(forge("app"), 0u);         // a headset
  EXPECT_EQ(forge("dashboard"), 0u);   // another dashboard
  EXPECT_GT(forge("floorposed"), 0u);  // the daemon's own identity: the control
}

// The team lead's dashboard on a secured domain: with its identity it shows the wearer;
// without one it joins nothing and shows no one.
TEST_F(SecurityTest, OnlyADashboardWithAnIdentitySeesTheWearers) {
  const platform::DdsSecurity app = Identity("pki", "app");
  dds_extra_ = SecurityConfig(Identity("pki", "floorposed"));
  StartDaemon("", &app);
  auto start_dashboard = [&](const std::string& name, std::vector<std::string> security) {
    std::vector<std::string> argv = {
        FLOORPOSE_PATH, "dashboard", "--plan", plan_path_, "--host",
        "127.0.0.1",    "--port",    "0",      "--domain", std::to_string(domain_),
        "--loopback"};
    argv.insert(argv.end(), security.begin(), security.end());
    const std::string log = (dir_ / (name + ".log")).string();
    auto process = std::make_unique<tools::ChildProcess>(argv, log);
    const int port = tools::DashboardPortFromLog(log, seconds(15));
    EXPECT_GT(port, 0) << "see " << log;
    return std::pair{std::move(process), port};
  };
  auto [trusted, trusted_port] = start_dashboard(
      "trusted", {"--security-dir", (dir_ / "pki").string(), "--identity", "dashboard"});
  auto [open, open_port] = start_dashboard("open", {});
  ASSERT_GT(trusted_port, 0);
  ASSERT_GT(open_port, 0);

  const sim::DemoWalk walk = Walk(/*pick_error_m=*/0.0, 1);
  Drive(*link_, walk, 0);
  ASSERT_TRUE(
      link_->WaitUntil([&] { return link_->plan_poses.size() == walk.steps.size(); }, seconds(10)));
  auto devices = [](int port) {
    httplib::Client http("127.0.0.1", port);
    auto r = http.Get("/api/devices");
    return r ? nlohmann::json::parse(r->body, nullptr, false) : nlohmann::json();
  };
  nlohmann::json seen;
  for (int i = 0; i < 100; ++i) {
    seen = devices(trusted_port);
    if (!seen.is_discarded() && seen.contains("devices") && !seen["devices"].empty() &&
        seen["devices"][0].contains("pose") &&
        seen["devices"][0]["pose"]["stamp_ns"] == link_->plan_poses.back().source_stamp_ns())
      break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_EQ(seen["devices"].size(), 1u) << seen.dump();
  EXPECT_EQ(seen["devices"][0]["id"], "hl-test");
  EXPECT_NEAR(seen["devices"][0]["pose"]["x"].get<double>(), link_->plan_poses.back().x(), 1e-3);
  const nlohmann::json nothing = devices(open_port);
  ASSERT_TRUE(nothing.contains("devices")) << nothing.dump();
  EXPECT_TRUE(nothing["devices"].empty()) << nothing.dump();
  EXPECT_EQ(trusted->Terminate(seconds(5)), 0);
  EXPECT_EQ(open->Terminate(seconds(5)), 0);
}

TEST_F(SecurityTest, ADaemonWhoseDocumentsAnotherCASignedDoesNotStart) {
  platform::DdsSecurity broken = Identity("pki", "floorposed");
  broken.governance = Identity("rogue", "app").governance;
  const std::string config_path = (dir_ / "floorposed.conf").string();
  std::ofstream(config_path) << platform::LoopbackDdsConfigText(domain_, "",
                                                                SecurityConfig(broken));
  tools::ChildProcess daemon({FLOORPOSED_PATH, "--config", config_path},
                             (dir_ / "floorposed.log").string());
  ASSERT_TRUE(daemon.started());
  EXPECT_EQ(daemon.Wait(seconds(10)), 1) << "see " << dir_;
  std::ifstream in(dir_ / "floorposed.log");
  const std::string log{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  EXPECT_NE(log.find("cannot start: DDS"), std::string::npos) << log;
}

}  // namespace
}  // namespace floorpose
