// A client of another DDS vendor and written from docs/protocol.md alone (fastdds_app,
// eProsima Fast DDS) drives a real floorposed (Cyclone DDS) on loopback: it finds the
// daemon, asks for its state, loads a plan by id, streams a simulated walk with its wall
// pick and receives every plan pose.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "platform/config.h"
#include "platform/dds.h"
#include "tests/daemon_test_util.h"
#include "tests/test_util.h"
#include "tools/lib/process.h"

namespace floorpose {
namespace {

namespace fs = std::filesystem;
using std::chrono::seconds;

class FastDdsInterop : public testing::TempDirTest {};

TEST_F(FastDdsInterop, AnAppOfAnotherVendorFollowsTheProtocolDocument) {
  const fs::path& dir = dir_;
  fs::create_directories(dir / "plans");
  fs::copy_file(FLOORPOSE_DEMO_PLAN, dir / "plans" / "office.geojson");

  const std::string recording = (dir / "walk.rec").string();
  ASSERT_EQ(testing::SimulateOfficeWalk(FLOORPOSE_DEMO_PLAN, 7, 60, recording), "");

  // The daemon starts without a plan: the app has to load one (section 7, step 4).
  const uint32_t domain = testing::UniqueDomain();
  const std::string config_path = (dir / "floorposed.conf").string();
  std::ofstream(config_path) << platform::LoopbackDdsConfigText(domain, "hl-fastdds")
                             << "plan_dir: \"" << (dir / "plans").string() << "\"\n"
                             << "status_period_s: 0.2\n"
                             // The walk comes at 10 times its pace: its updates are applied
                             // before the next pose, so that it ends TRACKING however loaded
                             // the machine is.
                             << "deterministic: true\n";
  tools::ChildProcess daemon({FLOORPOSED_PATH, "--config", config_path},
                             (dir / "floorposed.log").string());
  ASSERT_TRUE(daemon.started());

  const std::string out = (dir / "fastdds_app.out").string();
  tools::ChildProcess app(
      {FASTDDS_APP_PATH, "--domain", std::to_string(domain), "--device", "hl-fastdds",
       "--recording", recording, "--plan-id", "office", "--rate", "10"},
      out);
  ASSERT_EQ(app.Wait(seconds(100)), 0)
      << "fastdds_app failed; output in " << out << ", log in " << dir / "floorposed.log";
  EXPECT_EQ(daemon.Terminate(seconds(2)), 0);

  std::ifstream in(out);
  std::string line, json_line;
  while (std::getline(in, line))
    if (!line.empty() && line[0] == '{') json_line = line;
  ASSERT_FALSE(json_line.empty()) << "no JSON in " << out;
  const nlohmann::json r = nlohmann::json::parse(json_line);
  SCOPED_TRACE(json_line);

  EXPECT_EQ(r["plans"], nlohmann::json::array({"office"}));
  // get_state, load_plan and the recording's wall pick, each answered.
  ASSERT_EQ(r["replies"].size(), 3u);
  EXPECT_EQ(r["replies"][0]["command"], "get_state");
  EXPECT_EQ(r["replies"][1]["command"], "load_plan");
  EXPECT_EQ(r["replies"][2]["command"], "wall_pick");
  for (const auto& reply : r["replies"]) EXPECT_EQ(reply["ok"], true);
  // Every pose it sent came back as a plan pose, on the plan, and close to the truth.
  EXPECT_GT(r["poses_sent"].get<int>(), 100);
  EXPECT_GT(r["meshes_sent"].get<int>(), 10);
  EXPECT_EQ(r["plan_poses"], r["poses_sent"]);
  EXPECT_GT(r["scored_poses"].get<int>(), r["poses_sent"].get<int>() / 2);
  EXPECT_LT(r["mean_error_m"].get<double>(), 0.5);
  EXPECT_GT(r["reliable_poses"].get<int>(), 0);
  EXPECT_EQ(r["reliable_within_1m"], r["reliable_poses"]);
  EXPECT_EQ(r["final_state"], "TRACKING");
}

}  // namespace
}  // namespace floorpose
