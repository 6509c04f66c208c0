// `floorpose bench dashboard`: does the dashboard keep up with a team?
//
// Starts a real `floorpose dashboard` on a private loopback DDS domain, publishes the plan
// poses and statuses of N simulated wearers (as N daemons would) at R Hz each, and reads
// the event stream as B browsers would. Each PlanPose carries, as its source stamp, the
// CLOCK_REALTIME at which the bench wrote it, so a browser's receipt of it in the stream
// gives the latency through DDS, the dashboard and HTTP. Reports that latency, the poses
// that reached every browser's trails, whether every browser ends with every wearer's
// last pose, and the dashboard's CPU and memory.
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "core/random.h"
#include "platform/clock.h"
#include "platform/dds.h"
#include "platform/floor_plan_io.h"
#include "tools/floorpose/commands.h"
#include "tools/lib/dashboard.h"
#include "tools/lib/evaluation.h"
#include "tools/lib/process.h"
// clang-format off
#include <httplib.h>  // after Eigen: glibc's <resolv.h> defines _res, a name in Eigen
// clang-format on

namespace floorpose::tools {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using platform::Topic;
using Clock = std::chrono::steady_clock;

struct BenchDashboardOptions {
  std::string plan;  // empty: the bundled office
  int devices = 20;
  double rate_hz = 3.0;
  double seconds = 30.0;
  int browsers = 3;
  int domain = -1;
  bool json = false;
};

// One browser: reads /events, keeps what each wearer's trail and pose became.
struct BrowserStats {
  std::vector<double> latency_ms;        // of each pose that was a device's latest in a frame
  std::map<std::string, size_t> points;  // trail points received, per device
  std::map<std::string, int64_t> last_stamp;
  size_t frames = 0, bytes = 0, resets = 0;
  bool connected = false;
};

void ReadEvents(int port, const std::atomic<bool>& stop, BrowserStats* stats, std::mutex* mu) {
  httplib::Client http("127.0.0.1", port);
  http.set_read_timeout(5, 0);
  std::string buffer;
  http.Get("/events", [&](const char* data, size_t n) {
    const int64_t now = platform::WallClockNs();
    buffer.append(data, n);
    std::lock_guard lock(*mu);
    stats->connected = true;
    stats->bytes += n;
    for (size_t end; (end = buffer.find("\n\n")) != std::string::npos; buffer.erase(0, end + 2)) {
      if (buffer.rfind("data: ", 0) != 0) continue;
      const json frame = json::parse(buffer.substr(6, end - 6), nullptr, false);
      if (frame.is_discarded()) continue;
      ++stats->frames;
      for (const json& d : frame["devices"]) {
        const std::string id = d["id"];
        if (d.contains("trail")) {
          if (d["trail"]["reset"].get<bool>()) {
            ++stats->resets;
            stats->points[id] = 0;
          }
          stats->points[id] += d["trail"]["points"].size();
        }
        if (d.contains("pose")) {
          const int64_t stamp = d["pose"]["stamp_ns"];
          if (stamp > stats->last_stamp[id]) stats->latency_ms.push_back((now - stamp) * 1e-6);
          stats->last_stamp[id] = std::max(stats->last_stamp[id], stamp);
        }
      }
    }
    return !stop;
  });
}

// Each wearer walks a circle of 2 m about a point of the plan, at 1 m/s.
struct Wearer {
  std::string id;
  Eigen::Vector2d centre;
  double phase;
};

std::vector<Wearer> PlaceWearers(const FloorPlan& plan, int devices) {
  SplitMix64 rng(7);
  std::vector<Wearer> wearers;
  for (int k = 0; k < devices; ++k)
    wearers.push_back(
        {"hl-" + std::to_string(k),
         {rng.Uniform(plan.min.x(), plan.max.x()), rng.Uniform(plan.min.y(), plan.max.y())},
         rng.Uniform(0, 2 * M_PI)});
  return wearers;
}

// What the wearers sent, and what the dashboard process took meanwhile.
struct Sent {
  size_t poses = 0, failed = 0;
  std::map<std::string, int64_t> last;  // per wearer, its last pose's stamp
  double seconds = 0;
  double peak_rss_mb = 0;
  ProcSample before, after;
};

// The wearers' plan poses, in turn at rate_hz each, and a status about once a second each.
Sent SendPoses(const BenchDashboardOptions& o, const FloorPlan& plan, std::vector<Wearer>& wearers,
               platform::Participant& participant, const ChildProcess& dashboard) {
  platform::Writer poses(participant, Topic::kPlanPose);
  platform::Writer statuses(participant, Topic::kStatus);
  for (auto end = Clock::now() + std::chrono::seconds(10);
       poses.MatchedReaders() == 0 && Clock::now() < end;)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  Sent sent;
  sent.before = SampleProcess(dashboard.pid());
  const auto start = Clock::now();
  const auto period = std::chrono::duration<double>(1.0 / (o.rate_hz * o.devices));
  for (size_t tick = 0;; ++tick) {
    const auto at = start + std::chrono::duration_cast<Clock::duration>(period * tick);
    if (at - start > std::chrono::duration<double>(o.seconds)) break;
    std::this_thread::sleep_until(at);
    Wearer& w = wearers[tick % wearers.size()];
    const double t = std::chrono::duration<double>(Clock::now() - start).count();
    const double a = w.phase + t / 2.0;
    v1::PlanPose p;
    p.set_x(w.centre.x() + 2 * std::cos(a));
    p.set_y(w.centre.y() + 2 * std::sin(a));
    p.set_heading(a + M_PI / 2);
    p.set_source_stamp_ns(platform::WallClockNs());
    p.set_alignment_version(1);
    p.mutable_reliability()->set_flag(v1::Reliability::RELIABLE);
    p.mutable_reliability()->set_probability(0.97);
    p.mutable_reliability()->set_reason("registered");
    const platform::Envelope e{w.id, poses.NextSeq(), p.source_stamp_ns(), p.SerializeAsString(),
                               0};
    if (poses.Write(e)) {
      ++sent.poses;
      sent.last[w.id] = p.source_stamp_ns();
    } else {
      ++sent.failed;
    }
    if (tick % static_cast<size_t>(std::max(1.0, o.rate_hz)) == 0) {  // about 1 Hz a wearer
      v1::DaemonStatus s;
      s.set_state(v1::DaemonStatus::TRACKING);
      s.set_plan_id(plan.id);
      statuses.Write({w.id, statuses.NextSeq(), p.source_stamp_ns(), s.SerializeAsString(), 0});
    }
    if (tick % 100 == 0)
      sent.peak_rss_mb = std::max(sent.peak_rss_mb, SampleProcess(dashboard.pid()).rss_mb);
  }
  sent.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  sent.after = SampleProcess(dashboard.pid());
  sent.peak_rss_mb = std::max(sent.peak_rss_mb, sent.after.rss_mb);
  return sent;
}

// What every browser showed, all together.
struct Shown {
  std::vector<double> latency_ms;
  size_t points = 0, up_to_date = 0, frames = 0, bytes = 0;
};

Shown Tally(const std::vector<BrowserStats>& browsers, const Sent& sent) {
  Shown shown;
  for (const BrowserStats& b : browsers) {
    shown.latency_ms.insert(shown.latency_ms.end(), b.latency_ms.begin(), b.latency_ms.end());
    for (const auto& [id, n] : b.points) shown.points += n;
    for (const auto& [id, stamp] : sent.last)
      shown.up_to_date += b.last_stamp.count(id) && b.last_stamp.at(id) == stamp;
    shown.frames += b.frames;
    shown.bytes += b.bytes;
  }
  return shown;
}

void PrintDashboardBench(const BenchDashboardOptions& o, const Sent& sent, const Shown& shown) {
  const double s = sent.seconds;
  const double cpu_percent = 100.0 * (sent.after.cpu_s - sent.before.cpu_s) / s;
  const size_t expected = sent.poses * static_cast<size_t>(o.browsers);
  const size_t pairs = sent.last.size() * static_cast<size_t>(o.browsers);
  const std::vector<double>& latency = shown.latency_ms;
  if (o.json) {
    std::printf("%s\n", json{{"devices", o.devices},
                             {"rate_hz", o.rate_hz},
                             {"browsers", o.browsers},
                             {"seconds", s},
                             {"poses_sent", sent.poses},
                             {"poses_failed", sent.failed},
                             {"trail_points_expected", expected},
                             {"trail_points_shown", shown.points},
                             {"browsers_up_to_date", shown.up_to_date},
                             {"wearers_x_browsers", pairs},
                             {"latency_ms_p50", Percentile(latency, 0.5)},
                             {"latency_ms_p99", Percentile(latency, 0.99)},
                             {"latency_ms_max", Percentile(latency, 1.0)},
                             {"frames_per_s_per_browser", shown.frames / s / o.browsers},
                             {"kb_per_s_per_browser", shown.bytes / 1024.0 / s / o.browsers},
                             {"cpu_percent", cpu_percent},
                             {"rss_mb_peak", sent.peak_rss_mb}}
                            .dump()
                            .c_str());
    return;
  }
  std::printf("%d wearers at %.1f Hz for %.0f s, %d browsers\n", o.devices, o.rate_hz, s,
              o.browsers);
  std::printf("  poses sent %zu (failed %zu); trail points shown %zu of %zu\n", sent.poses,
              sent.failed, shown.points, expected);
  std::printf("  browsers ending on every wearer's last pose: %zu of %zu\n", shown.up_to_date,
              pairs);
  std::printf("  latency DDS -> dashboard -> browser: p50 %.1f ms, p99 %.1f ms, max %.1f ms\n",
              Percentile(latency, 0.5), Percentile(latency, 0.99), Percentile(latency, 1.0));
  std::printf("  per browser: %.1f frames/s, %.1f kB/s\n", shown.frames / s / o.browsers,
              shown.bytes / 1024.0 / s / o.browsers);
  std::printf("  dashboard: cpu %.1f%% of one core, rss %.1f MB (peak)\n", cpu_percent,
              sent.peak_rss_mb);
}

int RunBenchDashboard(const BenchDashboardOptions& o) {
  const std::string plan_path = o.plan.empty() ? DefaultDemoPlan() : o.plan;
  const FloorPlanParse plan = platform::LoadFloorPlan(plan_path);
  if (!plan.ok()) {
    spdlog::error("{}: {}", plan_path, plan.error);
    return 1;
  }
  const uint32_t domain =
      o.domain >= 0 ? static_cast<uint32_t>(o.domain) : 171 + static_cast<uint32_t>(getpid() % 30);
  const fs::path log = fs::temp_directory_path() /
                       ("floorpose-bench-dashboard-" + std::to_string(getpid()) + ".log");
  std::error_code ec;
  const std::string self = fs::read_symlink("/proc/self/exe", ec).string();
  ChildProcess dashboard({self, "dashboard", "--plan", plan_path, "--host", "127.0.0.1", "--port",
                          "0", "--domain", std::to_string(domain), "--loopback"},
                         log.string());
  const int port = DashboardPortFromLog(log.string(), std::chrono::seconds(15));
  if (port == 0) {
    spdlog::error("floorpose dashboard did not come up; see {}", log.string());
    return 1;
  }
  platform::Participant participant(domain, platform::LoopbackCycloneConfig());
  std::atomic<bool> stop{false};
  std::mutex mu;
  std::vector<BrowserStats> browsers(static_cast<size_t>(o.browsers));
  std::vector<std::thread> readers;
  for (BrowserStats& b : browsers) readers.emplace_back(ReadEvents, port, std::cref(stop), &b, &mu);
  for (auto end = Clock::now() + std::chrono::seconds(5); Clock::now() < end;) {
    std::lock_guard lock(mu);
    if (std::all_of(browsers.begin(), browsers.end(), [](auto& b) { return b.connected; })) break;
  }
  std::vector<Wearer> wearers = PlaceWearers(plan.plan, o.devices);
  const Sent sent = SendPoses(o, plan.plan, wearers, participant, dashboard);
  std::this_thread::sleep_for(std::chrono::seconds(1));  // the last frames
  stop = true;
  for (auto& r : readers) r.join();
  dashboard.Terminate(std::chrono::seconds(5));
  fs::remove(log, ec);
  const Shown shown = Tally(browsers, sent);
  PrintDashboardBench(o, sent, shown);
  return shown.points == sent.poses * browsers.size() &&
                 shown.up_to_date == sent.last.size() * browsers.size()
             ? 0
             : 1;
}

}  // namespace

Run AddBenchDashboardCommand(CLI::App& bench) {
  auto o = std::make_shared<BenchDashboardOptions>();
  CLI::App* app = bench.add_subcommand(
      "dashboard",
      "a real floorpose dashboard fed N wearers' plan poses over loopback DDS and read by B "
      "browsers: latency, poses shown, CPU, memory");
  app->add_option("--plan", o->plan, "floor plan (default: the bundled office)");
  app->add_option("--devices", o->devices, "wearers")
      ->check(CLI::Range(1, 200))
      ->capture_default_str();
  app->add_option("--rate", o->rate_hz, "plan poses a second per wearer")
      ->check(CLI::Range(0.1, 100.0))
      ->capture_default_str();
  app->add_option("--seconds", o->seconds, "how long")
      ->check(CLI::Range(1.0, 3600.0))
      ->capture_default_str();
  app->add_option("--browsers", o->browsers, "event streams read at once")
      ->check(CLI::Range(1, 32))
      ->capture_default_str();
  app->add_option("--domain", o->domain, "DDS domain id (default: 171-200, from the process id)");
  app->add_flag("--json", o->json, "print one JSON object");
  return [o] { return RunBenchDashboard(*o); };
}

}  // namespace floorpose::tools
