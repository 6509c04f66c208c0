// `floorpose bench daemon` as a user runs it: real floorposed processes, two headsets on
// one domain, every pose answered by its own daemon, and the JSON it promises. What it
// measures (latency, CPU, memory) is for docs/performance.md, not asserted here.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "tests/daemon_test_util.h"
#include "tests/test_util.h"
#include "tools/lib/process.h"

namespace floorpose {
namespace {

namespace fs = std::filesystem;

TEST(BenchDaemonTest, TwoHeadsetsEachAnsweredByItsOwnDaemon) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("bench-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string out = (dir / "out.json").string();
  // A minute of walk at 20 times real time, on a domain of its own.
  tools::ChildProcess bench({FLOORPOSE_PATH, "bench", "daemon", "--minutes", "1", "--speed", "20",
                             "--headsets", "2", "--domain", std::to_string(testing::UniqueDomain()),
                             "--logs", (dir / "logs").string(), "--json"},
                            out);
  ASSERT_TRUE(bench.started());
  ASSERT_EQ(bench.Wait(std::chrono::seconds(90)), 0) << testing::ReadText(out);

  const std::string text = testing::ReadText(out);
  const nlohmann::json j = nlohmann::json::parse(text.substr(text.rfind("\n{") + 1));
  for (const char* key :
       {"latency_ms_p50", "latency_ms_p99", "latency_ms_max", "rss_mb_peak", "rss_mb_10min",
        "rss_mb_final", "cpu_percent", "poses_in", "poses_out", "dropped"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["headsets"], 2);
  // 60 s of walk, a pose every 0.3 s, per headset; every one answered.
  EXPECT_EQ(j["poses_in"], 2 * 201);
  EXPECT_EQ(j["poses_out"], j["poses_in"]);
  EXPECT_EQ(j["dropped"], 0);
  EXPECT_TRUE(j["rss_mb_10min"].is_null());  // the walk was shorter than 10 minutes
  EXPECT_GT(j["rss_mb_peak"].get<double>(), 1.0);
  EXPECT_GT(j["registrations"].get<int>(), 0);
  EXPECT_TRUE(j["stopped_cleanly"].get<bool>());
  // Each daemon took only its own headset: its log says so, and it stopped with its own
  // poses counted.
  for (const char* device : {"bench-1", "bench-2"}) {
    const std::string log = testing::ReadText(dir / "logs" / (std::string(device) + ".log"));
    EXPECT_NE(log.find("as device '" + std::string(device) + "'"), std::string::npos) << device;
    EXPECT_NE(log.find("stopped: 201 poses in, 201 plan poses out"), std::string::npos) << log;
  }
  fs::remove_all(dir);
}

// --config: the daemon runs what the file adds (here fewer samples for the belief), and
// its updates are counted as registrations; a file that is not a configuration is refused.
TEST(BenchDaemonTest, TheDaemonRunsTheConfigurationGiven) {
  const fs::path dir =
      fs::path(::testing::TempDir()) / ("bench-config-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string config = (dir / "mcl.conf").string();
  std::ofstream(config) << "tracking { samples { min_samples: 200 max_samples: 400 } }\n";
  const std::string out = (dir / "out.json").string();
  tools::ChildProcess bench({FLOORPOSE_PATH, "bench", "daemon", "--minutes", "1", "--speed", "20",
                             "--domain", std::to_string(testing::UniqueDomain()), "--config",
                             config, "--logs", (dir / "logs").string(), "--json"},
                            out);
  ASSERT_TRUE(bench.started());
  ASSERT_EQ(bench.Wait(std::chrono::seconds(90)), 0) << testing::ReadText(out);
  const std::string text = testing::ReadText(out);
  const nlohmann::json j = nlohmann::json::parse(text.substr(text.rfind("\n{") + 1));
  EXPECT_EQ(j["poses_out"], j["poses_in"]);
  EXPECT_GT(j["registrations"].get<int>(), 0);
  const std::string log = testing::ReadText(dir / "logs" / "bench-1.log");
  EXPECT_NE(log.find("belief: "), std::string::npos) << log;
  // No belief holds more samples than the file allows (3000 by default).
  const std::regex samples(R"(belief: ([0-9]+) samples)");
  size_t beliefs = 0;
  for (auto it = std::sregex_iterator(log.begin(), log.end(), samples);
       it != std::sregex_iterator(); ++it, ++beliefs)
    EXPECT_LE(std::stoul((*it)[1].str()), 400u) << it->str();
  EXPECT_GT(beliefs, 0u);

  const std::string bad = (dir / "bad.conf").string();
  std::ofstream(bad) << "tracking { estimator: RULES }\n";
  const std::string bad_out = (dir / "bad.txt").string();
  tools::ChildProcess refused({FLOORPOSE_PATH, "bench", "daemon", "--config", bad}, bad_out);
  ASSERT_TRUE(refused.started());
  EXPECT_EQ(refused.Wait(std::chrono::seconds(30)), 2);
  EXPECT_NE(testing::ReadText(bad_out).find("bad.conf"), std::string::npos);
  fs::remove_all(dir);
}

// `floorpose bench dashboard`: a team of 20 wearers at 3 Hz, three browsers; every pose
// reaches every browser's trails and every browser ends on every wearer's last pose.
TEST(BenchDashboardTest, EveryPoseOfTwentyWearersReachesEveryBrowser) {
  const fs::path out =
      fs::path(::testing::TempDir()) / ("bench-dashboard-" + std::to_string(getpid()) + ".json");
  tools::ChildProcess bench({FLOORPOSE_PATH, "bench", "dashboard", "--seconds", "3", "--domain",
                             std::to_string(testing::UniqueDomain()), "--json"},
                            out.string());
  ASSERT_TRUE(bench.started());
  ASSERT_EQ(bench.Wait(std::chrono::seconds(60)), 0) << testing::ReadText(out);
  const std::string text = testing::ReadText(out);
  const nlohmann::json j = nlohmann::json::parse(text.substr(text.rfind('{')));
  EXPECT_GE(j["poses_sent"].get<int>(), 20 * 3 * 3);
  EXPECT_EQ(j["poses_failed"], 0);
  EXPECT_EQ(j["trail_points_shown"], j["trail_points_expected"]);
  EXPECT_EQ(j["browsers_up_to_date"], 60);
  EXPECT_EQ(j["wearers_x_browsers"], 60);
  for (const char* key : {"latency_ms_p50", "latency_ms_p99", "cpu_percent", "rss_mb_peak"})
    EXPECT_TRUE(j.contains(key)) << key;
  fs::remove(out);
}

}  // namespace
}  // namespace floorpose
