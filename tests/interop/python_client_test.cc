// The Python example client (tools/python/plan_poses.py), with Debian's python3-protobuf
// and the modules protoc generated, prints exactly the plan poses of a session recording.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "platform/recording.h"
#include "tests/daemon_test_util.h"
#include "tests/test_util.h"
#include "tools/lib/evaluation.h"
#include "tools/lib/process.h"

namespace floorpose {
namespace {

using std::chrono::seconds;

class PythonClientTest : public testing::TempDirTest {
 protected:
  // Runs the client on a recording; its exit code, and stdout and stderr in *out.
  std::optional<int> RunClient(const std::string& recording, std::string* out) {
    const std::string log = Path("client.out");
    tools::ChildProcess client(
        {"/usr/bin/env", "PYTHONPATH=" FLOORPOSE_PYTHON_PROTO_DIR, PYTHON3_PATH,
         FLOORPOSE_SOURCE_DIR "/tools/python/plan_poses.py", recording},
        log);
    const std::optional<int> code = client.Wait(seconds(60));
    std::ifstream in(log);
    *out = std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    return code;
  }
};

TEST_F(PythonClientTest, PrintsThePlanPosesOfASession) {
  const std::string walk = Path("walk.rec");
  std::string error = testing::SimulateOfficeWalk(FLOORPOSE_DEMO_PLAN, 9, 40, walk);
  ASSERT_EQ(error, "");
  // The session as the daemon would have published it (replay_test shows that it does).
  const std::string session_path = Path("session.rec");
  v1::FloorposedConfig config;
  config.set_plan_path(FLOORPOSE_DEMO_PLAN);
  tools::EvalReport report;
  {
    platform::RecordingWriter session(session_path);
    ASSERT_TRUE(tools::Evaluate(config, walk, tools::Baseline::kNone, &report, &error, &session))
        << error;
    ASSERT_TRUE(session.Flush()) << session.error();
  }
  ASSERT_GT(report.plan_poses.size(), 50u);

  std::string out;
  ASSERT_EQ(RunClient(session_path, &out), 0) << out;
  std::istringstream lines(out);
  std::string line;
  size_t i = 0, reliable = 0;
  while (std::getline(lines, line)) {
    if (line.empty() || line[0] == '#') continue;
    ASSERT_LT(i, report.plan_poses.size()) << line;
    const v1::PlanPose& want = report.plan_poses[i++];
    std::istringstream f(line);
    double stamp_s, x, y, heading, probability;
    std::string floor, flag;
    uint64_t version;
    ASSERT_TRUE(f >> stamp_s >> x >> y >> heading >> floor >> version >> flag >> probability)
        << line;
    EXPECT_NEAR(stamp_s, static_cast<double>(want.source_stamp_ns()) * 1e-9, 1e-3);
    EXPECT_NEAR(x, want.x(), 1e-6);
    EXPECT_NEAR(y, want.y(), 1e-6);
    EXPECT_NEAR(heading, want.heading(), 1e-6);
    EXPECT_EQ(floor, want.floor());
    EXPECT_EQ(version, want.alignment_version());
    EXPECT_EQ(flag, v1::Reliability::Flag_Name(want.reliability().flag()));
    EXPECT_NEAR(probability, want.reliability().probability(), 1e-3);
    reliable += want.reliability().flag() == v1::Reliability::RELIABLE;
  }
  EXPECT_EQ(i, report.plan_poses.size());
  EXPECT_NE(
      out.find("# " + std::to_string(i) + " plan poses, " + std::to_string(reliable) + " RELIABLE"),
      std::string::npos)
      << out;
}

TEST_F(PythonClientTest, SaysWhatIsWrongWithACorruptFile) {
  const std::string bad = Write("bad.rec",
                                "FPREC01\n\x7f"
                                "short");
  std::string out;
  EXPECT_EQ(RunClient(bad, &out), 1);
  EXPECT_NE(out.find("runs past the end of the file"), std::string::npos) << out;
  const std::string other = Write("other.txt", "not a recording");
  EXPECT_EQ(RunClient(other, &out), 1);
  EXPECT_NE(out.find("not a floorpose recording"), std::string::npos) << out;
}

}  // namespace
}  // namespace floorpose
