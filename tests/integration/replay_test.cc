// A simulated recording replayed over DDS through a real floorposed (deterministic mode)
// gives exactly the plan poses `floorpose eval` computes from the same file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "platform/config.h"
#include "platform/dds.h"
#include "tests/daemon_test_util.h"
#include "tests/test_util.h"
#include "tools/lib/evaluation.h"
#include "tools/lib/headset_link.h"
#include "tools/lib/process.h"

namespace floorpose {
namespace {

namespace fs = std::filesystem;
using std::chrono::seconds;

class ReplayTest : public testing::TempDirTest {};

TEST_F(ReplayTest, DaemonGivesTheSamePlanPosesAsEval) {
  const fs::path& dir = dir_;
  const std::string recording = (dir / "walk.rec").string();
  std::string error = testing::SimulateOfficeWalk(FLOORPOSE_DEMO_PLAN, 5, 60, recording);
  ASSERT_EQ(error, "");

  // The offline run.
  v1::FloorposedConfig config;
  config.set_plan_path(FLOORPOSE_DEMO_PLAN);
  tools::EvalReport report;
  ASSERT_TRUE(tools::Evaluate(config, recording, tools::Baseline::kNone, &report, &error)) << error;
  ASSERT_GT(report.plan_poses.size(), 100u);
  ASSERT_GT(report.accepted, 0u) << "the walk should exercise registration";

  // The live run: floorposed in deterministic mode, the recording replayed over DDS.
  const uint32_t domain = testing::UniqueDomain();
  const std::string config_path = (dir / "floorposed.conf").string();
  std::ofstream(config_path) << platform::LoopbackDdsConfigText(domain, "sim-headset")
                             << "plan_path: \"" << FLOORPOSE_DEMO_PLAN << "\"\n"
                             << "deterministic: true\nstatus_period_s: 0.2\n";
  tools::ChildProcess daemon({FLOORPOSED_PATH, "--config", config_path},
                             (dir / "floorposed.log").string());
  tools::HeadsetLink link(domain, platform::LoopbackCycloneConfig(), "sim-headset");
  ASSERT_TRUE(link.WaitUntil([&] { return link.status.has_value(); }, seconds(15)))
      << "floorposed did not come up; log in " << dir;
  tools::ChildProcess replay({FLOORPOSE_PATH, "replay", "--recording", recording, "--domain",
                              std::to_string(domain), "--loopback", "--rate", "10"},
                             (dir / "replay.log").string());
  ASSERT_TRUE(link.WaitUntil([&] { return link.plan_poses.size() >= report.plan_poses.size(); },
                             seconds(90)))
      << link.plan_poses.size() << " of " << report.plan_poses.size() << " plan poses; logs in "
      << dir;
  EXPECT_EQ(replay.Wait(seconds(30)), 0);
  EXPECT_EQ(daemon.Terminate(seconds(2)), 0);

  ASSERT_EQ(link.plan_poses.size(), report.plan_poses.size());
  size_t differing = 0;
  for (size_t i = 0; i < report.plan_poses.size(); ++i) {
    const v1::PlanPose& live = link.plan_poses[i];
    const v1::PlanPose& offline = report.plan_poses[i];
    ASSERT_EQ(live.source_stamp_ns(), offline.source_stamp_ns()) << "pose " << i;
    const bool same = live.x() == offline.x() && live.y() == offline.y() &&
                      live.heading() == offline.heading() &&
                      live.alignment_version() == offline.alignment_version() &&
                      live.reliability().flag() == offline.reliability().flag();
    if (!same && differing++ < 5)
      ADD_FAILURE() << "pose " << i << ": live " << live.ShortDebugString() << "\n  offline "
                    << offline.ShortDebugString();
  }
  EXPECT_EQ(differing, 0u);
}

}  // namespace
}  // namespace floorpose
