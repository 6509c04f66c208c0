// `floorpose bench daemon`: floorposed's footprint on the puck, measured from outside.
//
// Starts real floorposed processes, one per simulated headset, all on one private loopback
// DDS domain (each takes only its own device), and plays each a long simulated walk over
// the bundled office plan (mesh deltas, poses, a wall pick) faster than real time. It
// measures what the wearer's puck pays:
//  - pose latency: from the bench writing a HeadsetPose to the daemon writing the PlanPose
//    made from it (its DDS source timestamp; both on CLOCK_REALTIME, one clock for every
//    process of the machine), and the round trip until that PlanPose is back in the bench
//    (CLOCK_MONOTONIC, stamped by a thread that blocks on the plan-pose reader);
//  - registration times, from each daemon's own log lines;
//  - CPU: utime + stime of the daemon (/proc/PID/stat) per minute of walk, and as a share of
//    one core at real time (CPU seconds over walk seconds);
//  - memory: resident set (/proc/PID/status VmRSS) after 10 minutes of walk and at the end,
//    and its high-water mark (VmHWM);
//  - poses sent, answered, dropped (never answered) and late (back after --late-ms).
// Played faster than real time, the daemon's per-second costs (status, wake-ups) count
// less than they would: `--speed 1` gives the CPU share exactly, in real time.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "core/sim/simulator.h"
#include "platform/clock.h"
#include "platform/config.h"
#include "platform/dds.h"
#include "platform/floor_plan_io.h"
#include "tools/floorpose/commands.h"
#include "tools/lib/evaluation.h"
#include "tools/lib/headset_link.h"
#include "tools/lib/headset_messages.h"
#include "tools/lib/process.h"

namespace floorpose::tools {
namespace {

namespace fs = std::filesystem;
using platform::Topic;

struct BenchDaemonOptions {
  std::string plan;  // empty: the bundled office
  double minutes = 30.0;
  double speed = 10.0;
  double rate_scale = 1.0;
  int headsets = 1;
  uint64_t seed = 1;
  int domain = -1;
  double late_ms = 50.0;
  std::string floorposed;
  std::string logs;         // keep the daemons' logs here
  std::string latency_csv;  // every pose's latency here
  std::string config;       // more of the daemon's configuration (text format)
  bool json = false;
};

// Update times (ms) from a daemon's log: "belief: ..., polished true, 12.3 ms: ...".
std::vector<double> RegistrationTimes(const std::string& log_path) {
  static const std::regex kLine(R"(belief: .*polished (?:true|false), ([0-9.]+) ms)");
  std::vector<double> out;
  std::ifstream in(log_path);
  std::string line;
  std::smatch m;
  while (std::getline(in, line))
    if (std::regex_search(line, m, kLine)) out.push_back(std::stod(m[1].str()));
  return out;
}

struct Headset {
  std::string device;
  sim::Simulation walk;
  std::unordered_map<int64_t, size_t> step_of_stamp;
  std::vector<std::atomic<int64_t>> sent_ns;       // per step: when its pose was written...
  std::vector<std::atomic<int64_t>> sent_wall_ns;  // ...on CLOCK_MONOTONIC and _REALTIME
  std::vector<double> latency_ms;     // pose written to plan pose written (receiver thread...
  std::vector<double> round_trip_ms;  // ...and to plan pose back here (until it is joined)
  std::vector<size_t> latency_step;   // ...and the step of each
  std::vector<uint8_t> answered;
  size_t mesh_deltas = 0;
  std::string log_path;
  std::unique_ptr<ChildProcess> daemon;
  std::unique_ptr<HeadsetLink> link;
  ProcSample at_10min, at_end;
};

double Max(const std::vector<double>& v) {
  return v.empty() ? 0 : *std::max_element(v.begin(), v.end());
}

// The walks: the office scenario (furniture, people, SLAM drift), poses and mesh updates
// rate_scale times as often as a HoloLens sends them. A surface changes no faster with more
// poses: above x1 each delta also goes out as `resends` UPDATED copies (every one decoded,
// extracted and stored again by the daemon).
bool SimulateHeadsets(const FloorPlan& plan, const BenchDaemonOptions& o, int resends,
                      std::vector<Headset>* headsets) {
  *headsets = std::vector<Headset>(static_cast<size_t>(o.headsets));
  for (int h = 0; h < o.headsets; ++h) {
    Headset& hs = (*headsets)[static_cast<size_t>(h)];
    hs.device = "bench-" + std::to_string(h + 1);
    sim::SimulatorOptions so;
    so.seed = o.seed + static_cast<uint64_t>(h);
    so.scenario = sim::Scenario::kOffice;
    so.target_length_m = 1e9;
    so.max_duration_s = o.minutes * 60.0;
    so.pose_period_s /= o.rate_scale;
    so.update_after_s /= o.rate_scale;
    hs.walk = sim::Simulate(plan, so);
    if (!hs.walk.ok()) {
      spdlog::error("simulating {}: {}", hs.device, hs.walk.error);
      return false;
    }
    for (size_t k = 0; k < hs.walk.steps.size(); ++k) {
      hs.step_of_stamp[hs.walk.steps[k].stamp_ns] = k;
      hs.mesh_deltas += hs.walk.steps[k].meshes.size() * resends;
    }
    hs.sent_ns = std::vector<std::atomic<int64_t>>(hs.walk.steps.size());
    hs.sent_wall_ns = std::vector<std::atomic<int64_t>>(hs.walk.steps.size());
    hs.answered.assign(hs.walk.steps.size(), 0);
    hs.latency_ms.reserve(hs.walk.steps.size());
    hs.round_trip_ms.reserve(hs.walk.steps.size());
  }
  return true;
}

// --config's text, checked to parse as the daemon's configuration ("" without one).
bool ReadExtraConfig(const std::string& path, std::string* text) {
  text->clear();
  if (path.empty()) return true;
  v1::FloorposedConfig parsed;
  std::string error;
  if (platform::ReadFile(path, 1u << 20, text, &error) &&
      platform::ParseConfig(*text, &parsed, &error))
    return true;
  spdlog::error("--config {}: {}", path, error);
  return false;
}

// One floorposed per headset, each with its own configuration and state directory under
// `tmp`, and the headset's link to it; true once every daemon answers.
bool StartDaemons(const BenchDaemonOptions& o, const std::string& plan_path,
                  const std::string& extra_config, uint32_t domain, const fs::path& tmp,
                  std::vector<Headset>& headsets) {
  const std::string floorposed = o.floorposed.empty() ? FindFloorposed() : o.floorposed;
  for (Headset& hs : headsets) {
    const fs::path dir = tmp / hs.device;
    fs::create_directories(dir);
    const std::string config_path = (dir / "floorposed.conf").string();
    std::ofstream(config_path) << platform::LoopbackDdsConfigText(domain, hs.device)
                               << "plan_path: \"" << fs::absolute(plan_path).string()
                               << "\"\nlog_level: \"info\"\nstate_dir: \"" << dir.string() << "\"\n"
                               << extra_config;
    hs.log_path = o.logs.empty() ? (dir / "floorposed.log").string()
                                 : (fs::path(o.logs) / (hs.device + ".log")).string();
    if (!o.logs.empty()) fs::create_directories(o.logs);
    hs.daemon = std::make_unique<ChildProcess>(
        std::vector<std::string>{floorposed, "--config", config_path}, hs.log_path);
    hs.link = std::make_unique<HeadsetLink>(domain, platform::LoopbackCycloneConfig(), hs.device);
  }
  for (Headset& hs : headsets)
    if (!hs.link->WaitForDaemon(std::chrono::seconds(15))) {
      spdlog::error("floorposed for {} did not come up on domain {} (see {})", hs.device, domain,
                    hs.log_path);
      return false;
    }
  return true;
}

// Plan poses back from every daemon, stamped as they arrive, on a thread that blocks on
// the reader; each headset's first answer to each of its poses is kept.
class PlanPoseReceiver {
 public:
  PlanPoseReceiver(platform::Participant& participant, std::vector<Headset>& headsets)
      : reader_(participant, Topic::kPlanPose), waiter_(participant) {
    waiter_.Attach(reader_);
    for (Headset& hs : headsets) by_device_[hs.device] = &hs;
    thread_ = std::thread([this] { Run(); });
  }
  ~PlanPoseReceiver() { Stop(); }

  size_t answered() const { return answered_.load(); }
  // Joins the thread: the headsets' latencies are the caller's to read after.
  void Stop() {
    if (!thread_.joinable()) return;
    stop_ = true;
    waiter_.Wake();
    thread_.join();
  }

 private:
  void Run() {
    while (!stop_.load()) {
      waiter_.Wait(std::chrono::milliseconds(50));
      const int64_t now = platform::MonotonicNs();
      for (const platform::Envelope& e : reader_.Take(1024)) Receive(e, now);
    }
  }

  void Receive(const platform::Envelope& e, int64_t now) {
    auto it = by_device_.find(e.device_id);
    v1::PlanPose p;
    if (it == by_device_.end() || !p.ParseFromString(e.payload)) return;
    Headset& hs = *it->second;
    auto step = hs.step_of_stamp.find(p.source_stamp_ns());
    if (step == hs.step_of_stamp.end() || hs.answered[step->second]) return;
    hs.answered[step->second] = 1;
    hs.latency_ms.push_back(
        static_cast<double>(e.source_timestamp_ns - hs.sent_wall_ns[step->second].load()) * 1e-6);
    hs.round_trip_ms.push_back(static_cast<double>(now - hs.sent_ns[step->second].load()) * 1e-6);
    hs.latency_step.push_back(step->second);
    answered_.fetch_add(1);
  }

  platform::Reader reader_;
  platform::Waiter waiter_;
  std::unordered_map<std::string, Headset*> by_device_;
  std::atomic<bool> stop_{false};
  std::atomic<size_t> answered_{0};
  std::thread thread_;
};

bool WaitFor(const std::function<bool()>& pred, std::chrono::seconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (!pred() && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  return pred();
}

struct Played {
  size_t poses_sent = 0;
  double played_s = 0;         // wall-clock seconds from the first answered pose to the end
  bool sampled_10min = false;  // the walk reached 10 minutes, and memory was sampled there
};

// Plays every walk at o.speed times real time: all start at the same virtual time with the
// same pose period, the longest one paces them all.
Played PlayWalks(const BenchDaemonOptions& o, int resends, std::vector<Headset>& headsets,
                 const PlanPoseReceiver& receiver) {
  const HeadsetFrame frame = HeadsetFrame::kUnityLeftHandedYUp;
  const sim::Simulation& clock =
      std::max_element(headsets.begin(), headsets.end(), [](const Headset& a, const Headset& b) {
        return a.walk.steps.size() < b.walk.steps.size();
      })->walk;
  const int64_t first_stamp = headsets.front().walk.steps.front().stamp_ns;
  const int64_t ten_minutes_ns = first_stamp + static_cast<int64_t>(600e9);
  Played played;
  auto t0 = std::chrono::steady_clock::now();
  for (size_t k = 0; k < clock.steps.size(); ++k) {
    const int64_t stamp = clock.steps[k].stamp_ns;
    std::this_thread::sleep_until(
        t0 + std::chrono::nanoseconds(static_cast<int64_t>((stamp - first_stamp) / o.speed)));
    for (Headset& hs : headsets) {
      if (k >= hs.walk.steps.size()) continue;
      const sim::SimulatedStep& step = hs.walk.steps[k];
      for (const sim::SimMesh& m : step.meshes) {
        v1::MeshDelta delta = ToMeshDelta(m, frame, step.stamp_ns);
        for (int copy = 0; copy < resends; ++copy) {
          if (copy == 1 && delta.change() == v1::MeshDelta::ADDED)
            delta.set_change(v1::MeshDelta::UPDATED);
          hs.link->Send(Topic::kMeshDelta, delta, step.stamp_ns);
        }
      }
      hs.sent_wall_ns[k] = platform::WallClockNs();
      hs.sent_ns[k] = platform::MonotonicNs();
      hs.link->Send(Topic::kHeadsetPose, ToHeadsetPose(step.slam, frame, step.stamp_ns),
                    step.stamp_ns);
      ++played.poses_sent;
      if (k == hs.walk.pick_step)
        hs.link->Send(Topic::kCommand,
                      ToWallPickCommand(hs.walk.pick, hs.walk.pick_height_m, frame, 1),
                      step.stamp_ns);
    }
    if (k == 0) {
      // The plan-pose writers keep only their latest pose for a reader they match late:
      // the walk goes on, from now, once every daemon has answered its first pose.
      if (!WaitFor([&] { return receiver.answered() >= played.poses_sent; },
                   std::chrono::seconds(15)))
        spdlog::warn("the first poses were not all answered within 15 s");
      t0 = std::chrono::steady_clock::now();
    }
    if (!played.sampled_10min && stamp >= ten_minutes_ns) {
      for (Headset& hs : headsets) hs.at_10min = SampleProcess(hs.daemon->pid());
      played.sampled_10min = true;
    }
  }
  WaitFor([&] { return receiver.answered() >= played.poses_sent; }, std::chrono::seconds(5));
  played.played_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return played;
}

// Everything, all headsets together; memory and CPU per daemon (the worst, and the mean).
struct Totals {
  std::vector<double> latency, round_trip, registrations;
  size_t dropped = 0, late = 0, wall_points = 0, meshes = 0;
  double rss_peak = 0, rss_10 = 0, rss_final = 0, cpu_s = 0;
};

Totals Total(const BenchDaemonOptions& o, const std::vector<Headset>& headsets,
             bool sampled_10min) {
  Totals t;
  for (const Headset& hs : headsets) {
    t.latency.insert(t.latency.end(), hs.latency_ms.begin(), hs.latency_ms.end());
    t.round_trip.insert(t.round_trip.end(), hs.round_trip_ms.begin(), hs.round_trip_ms.end());
    t.dropped += hs.walk.steps.size() - hs.latency_ms.size();
    t.late += static_cast<size_t>(std::count_if(hs.round_trip_ms.begin(), hs.round_trip_ms.end(),
                                                [&](double ms) { return ms > o.late_ms; }));
    const std::vector<double> r = RegistrationTimes(hs.log_path);
    t.registrations.insert(t.registrations.end(), r.begin(), r.end());
    t.rss_peak = std::max(t.rss_peak, hs.at_end.hwm_mb);
    t.rss_10 = std::max(t.rss_10, sampled_10min ? hs.at_10min.rss_mb : 0.0);
    t.rss_final = std::max(t.rss_final, hs.at_end.rss_mb);
    t.cpu_s += hs.at_end.cpu_s / o.headsets;
    if (hs.link->status) {
      t.wall_points = std::max<size_t>(t.wall_points, hs.link->status->wall_points());
      t.meshes = std::max<size_t>(t.meshes, hs.link->status->live_meshes());
    }
  }
  return t;
}

void WriteLatencyCsv(const std::string& path, const std::vector<Headset>& headsets) {
  const int64_t first_stamp = headsets.front().walk.steps.front().stamp_ns;
  std::ofstream csv(path);
  csv << "device,t_s,latency_ms,round_trip_ms,mesh_deltas_before\n";
  for (const Headset& hs : headsets)
    for (size_t i = 0; i < hs.latency_ms.size(); ++i) {
      const sim::SimulatedStep& step = hs.walk.steps[hs.latency_step[i]];
      csv << hs.device << ',' << static_cast<double>(step.stamp_ns - first_stamp) * 1e-9 << ','
          << hs.latency_ms[i] << ',' << hs.round_trip_ms[i] << ',' << step.meshes.size() << '\n';
    }
}

void PrintJson(const BenchDaemonOptions& o, const std::vector<Headset>& headsets,
               const Played& played, const Totals& t, bool clean) {
  const double walk_s = headsets.front().walk.duration_s;
  const nlohmann::json j = {
      {"headsets", o.headsets},
      {"speed", o.speed},
      {"rate_scale", o.rate_scale},
      {"walk_s", walk_s},
      {"walk_m", headsets.front().walk.length_m},
      {"mesh_deltas", headsets.front().mesh_deltas},
      {"latency_ms_p50", Percentile(t.latency, 0.5)},
      {"latency_ms_p99", Percentile(t.latency, 0.99)},
      {"latency_ms_max", Max(t.latency)},
      {"round_trip_ms_p50", Percentile(t.round_trip, 0.5)},
      {"round_trip_ms_p99", Percentile(t.round_trip, 0.99)},
      {"round_trip_ms_max", Max(t.round_trip)},
      {"registrations", t.registrations.size()},
      {"registration_ms_p50", Percentile(t.registrations, 0.5)},
      {"registration_ms_p99", Percentile(t.registrations, 0.99)},
      {"registration_ms_max", Max(t.registrations)},
      {"rss_mb_peak", t.rss_peak},
      {"rss_mb_10min", played.sampled_10min ? nlohmann::json(t.rss_10) : nlohmann::json(nullptr)},
      {"rss_mb_final", t.rss_final},
      {"cpu_s_per_walk_minute", t.cpu_s / (walk_s / 60.0)},
      {"cpu_percent", 100.0 * t.cpu_s / walk_s},
      {"cpu_percent_played", 100.0 * t.cpu_s / played.played_s},
      {"poses_in", played.poses_sent},
      {"poses_out", t.latency.size()},
      {"dropped", t.dropped},
      {"late", t.late},
      {"wall_points", t.wall_points},
      {"live_meshes", t.meshes},
      {"stopped_cleanly", clean},
  };
  std::printf("%s\n", j.dump().c_str());
}

void PrintText(const BenchDaemonOptions& o, const std::vector<Headset>& headsets,
               const Played& played, const Totals& t, bool clean) {
  const double walk_s = headsets.front().walk.duration_s;
  std::printf("  pose written to plan pose written      p50 %.2f  p99 %.2f  max %.2f ms\n",
              Percentile(t.latency, 0.5), Percentile(t.latency, 0.99), Max(t.latency));
  std::printf("  ...and back at the headset             p50 %.2f  p99 %.2f  max %.2f ms\n",
              Percentile(t.round_trip, 0.5), Percentile(t.round_trip, 0.99), Max(t.round_trip));
  std::printf(
      "  poses sent / answered                  %zu / %zu: %zu dropped, %zu late (> %g ms)\n",
      played.poses_sent, t.latency.size(), t.dropped, t.late, o.late_ms);
  std::printf("  registrations                          %zu: p50 %.1f  p99 %.1f  max %.1f ms\n",
              t.registrations.size(), Percentile(t.registrations, 0.5),
              Percentile(t.registrations, 0.99), Max(t.registrations));
  std::printf(
      "  CPU per daemon                         %.2f s per minute of walk: %.2f%% of a core at "
      "real time (%.1f%% while played)\n",
      t.cpu_s / (walk_s / 60.0), 100.0 * t.cpu_s / walk_s, 100.0 * t.cpu_s / played.played_s);
  if (played.sampled_10min)
    std::printf(
        "  RSS per daemon (worst)                 peak %.1f MB, after 10 min %.1f MB, "
        "final %.1f MB\n",
        t.rss_peak, t.rss_10, t.rss_final);
  else
    std::printf("  RSS per daemon (worst)                 peak %.1f MB, final %.1f MB\n",
                t.rss_peak, t.rss_final);
  std::printf("  wall store at the end                  %zu points in %zu meshes\n", t.wall_points,
              t.meshes);
  for (const Headset& hs : headsets)
    std::printf("  %-8s  cpu %.1f s  rss %.1f MB (peak %.1f)  answered %zu / %zu\n",
                hs.device.c_str(), hs.at_end.cpu_s, hs.at_end.rss_mb, hs.at_end.hwm_mb,
                hs.latency_ms.size(), hs.walk.steps.size());
  std::printf("  floorposed stopped                     %s\n", clean ? "cleanly" : "NOT cleanly");
}

int RunBenchDaemon(const BenchDaemonOptions& o) {
  const std::string plan_path = o.plan.empty() ? DefaultDemoPlan() : o.plan;
  const FloorPlanParse plan = platform::LoadFloorPlan(plan_path);
  if (!plan.ok()) {
    spdlog::error("{}", plan.error);
    return 1;
  }
  const uint32_t domain =
      o.domain >= 0 ? static_cast<uint32_t>(o.domain) : 201 + static_cast<uint32_t>(getpid() % 30);
  const fs::path tmp = fs::temp_directory_path() / ("floorpose-bench-" + std::to_string(getpid()));
  fs::create_directories(tmp);
  // Removed on every way out, after the daemons (declared later, stopped first) are gone.
  struct RemoveDir {
    fs::path dir;
    ~RemoveDir() {
      std::error_code ignored;
      fs::remove_all(dir, ignored);
    }
  } remove_tmp{tmp};
  // Made first, so that it owns the domain in this process and outlives the headsets'.
  platform::Participant receiver_participant(domain, platform::LoopbackCycloneConfig());
  const int resends = std::max(1, static_cast<int>(std::lround(o.rate_scale)));
  std::vector<Headset> headsets;
  if (!SimulateHeadsets(plan.plan, o, resends, &headsets)) return 1;
  std::string extra_config;
  if (!ReadExtraConfig(o.config, &extra_config)) return 2;
  if (!StartDaemons(o, plan_path, extra_config, domain, tmp, headsets)) return 1;
  PlanPoseReceiver receiver(receiver_participant, headsets);
  if (!o.json)
    std::printf(
        "floorpose bench daemon: %d headset(s) and daemon(s) on domain %u, plan %s\n"
        "  walk %.0f m in %.1f min each (%zu poses, %zu mesh deltas), rates x%g, played at "
        "%gx real time\n",
        o.headsets, domain, plan_path.c_str(), headsets.front().walk.length_m,
        headsets.front().walk.duration_s / 60.0, headsets.front().walk.steps.size(),
        headsets.front().mesh_deltas, o.rate_scale, o.speed);
  std::fflush(stdout);
  const Played played = PlayWalks(o, resends, headsets, receiver);
  for (Headset& hs : headsets) {
    hs.at_end = SampleProcess(hs.daemon->pid());
    // The last status, for the store's size and the daemon's own counters.
    hs.link->WaitUntil(
        [&] {
          return hs.link->status && hs.link->status->counters().poses_in() >= hs.walk.steps.size();
        },
        std::chrono::seconds(3));
  }
  receiver.Stop();
  bool clean = true;
  for (Headset& hs : headsets) {
    const auto code = hs.daemon->Terminate(std::chrono::seconds(5));
    clean = clean && code && *code == 0;
  }
  const Totals totals = Total(o, headsets, played.sampled_10min);
  if (!o.latency_csv.empty()) WriteLatencyCsv(o.latency_csv, headsets);
  if (o.json)
    PrintJson(o, headsets, played, totals, clean);
  else
    PrintText(o, headsets, played, totals, clean);
  if (o.logs.empty() && clean) fs::remove_all(tmp);
  return clean && totals.dropped == 0 ? 0 : 1;
}

}  // namespace

Run AddBenchDaemonCommand(CLI::App& bench) {
  auto o = std::make_shared<BenchDaemonOptions>();
  CLI::App* app = bench.add_subcommand(
      "daemon",
      "real floorposed processes fed long simulated walks over loopback DDS: pose latency, "
      "registration time, CPU, memory, lost poses");
  app->add_option("--plan", o->plan, "floor plan (default: the bundled office)");
  app->add_option("--minutes", o->minutes, "walk length, minutes of simulated time")
      ->check(CLI::Range(0.1, 600.0))
      ->capture_default_str();
  app->add_option("--speed", o->speed, "playback speed, times real time")
      ->check(CLI::Range(0.1, 1000.0))
      ->capture_default_str();
  app->add_option("--rate-scale", o->rate_scale,
                  "poses and mesh deltas this many times as often as a HoloLens sends them "
                  "(poses closer together; each delta also re-sent as UPDATED copies)")
      ->check(CLI::Range(0.1, 100.0))
      ->capture_default_str();
  app->add_option("--headsets", o->headsets, "headsets, each with its own daemon, on one domain")
      ->check(CLI::Range(1, 32))
      ->capture_default_str();
  app->add_option("--seed", o->seed, "simulation seed of the first headset")->capture_default_str();
  app->add_option("--domain", o->domain, "DDS domain id (default: 201-230, from the process id)");
  app->add_option("--late-ms", o->late_ms, "a plan pose later than this is late")
      ->capture_default_str();
  app->add_option("--floorposed", o->floorposed, "floorposed binary (default: beside floorpose)");
  app->add_option("--logs", o->logs, "keep the daemons' logs in this directory");
  app->add_option("--latency-csv", o->latency_csv,
                  "write every pose's latency here (device, walk time, ms, mesh deltas before it)");
  app->add_option("--config", o->config,
                  "more of the daemons' configuration, text format (for example "
                  "'tracking { samples { max_samples: 1000 } }'); not dds, plan_path, "
                  "log_level or state_dir")
      ->check(CLI::ExistingFile);
  app->add_flag("--json", o->json, "print one JSON object");
  return [o] {
    try {
      return RunBenchDaemon(*o);
    } catch (const std::exception& e) {  // DDS would not start: the daemons are stopped
      spdlog::error("bench daemon: {}", e.what());
      return 1;
    }
  };
}

}  // namespace floorpose::tools
