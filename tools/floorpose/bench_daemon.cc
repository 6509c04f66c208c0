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
  const std::string floorposed = o.floorposed.empty() ? FindFloorposed() : o.floorposed;
  const HeadsetFrame frame = HeadsetFrame::kUnityLeftHandedYUp;

  // Made first, so that it owns the domain in this process and outlives the headsets'.
  platform::Participant receiver_participant(domain, platform::LoopbackCycloneConfig());

  // The walks: the office scenario (furniture, people, SLAM drift), poses and mesh
  // updates rate_scale times as often as a HoloLens sends them.
  // A surface changes no faster with more poses: above x1 each delta also goes out as
  // that many UPDATED copies (every one decoded, extracted and stored again by the daemon).
  const int resends = std::max(1, static_cast<int>(std::lround(o.rate_scale)));
  std::vector<Headset> headsets(static_cast<size_t>(o.headsets));
  for (int h = 0; h < o.headsets; ++h) {
    Headset& hs = headsets[static_cast<size_t>(h)];
    hs.device = "bench-" + std::to_string(h + 1);
    sim::SimulatorOptions so;
    so.seed = o.seed + static_cast<uint64_t>(h);
    so.scenario = sim::Scenario::kOffice;
    so.target_length_m = 1e9;
    so.max_duration_s = o.minutes * 60.0;
    so.pose_period_s /= o.rate_scale;
    so.update_after_s /= o.rate_scale;
    hs.walk = sim::Simulate(plan.plan, so);
    if (!hs.walk.ok()) {
      spdlog::error("simulating {}: {}", hs.device, hs.walk.error);
      return 1;
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

  std::string extra_config;
  if (!o.config.empty()) {
    v1::FloorposedConfig parsed;
    std::string error;
    if (!platform::ReadFile(o.config, 1u << 20, &extra_config, &error) ||
        !platform::ParseConfig(extra_config, &parsed, &error)) {
      spdlog::error("--config {}: {}", o.config, error);
      return 2;
    }
  }
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
      return 1;
    }

  // Plan poses back, stamped as they arrive.
  platform::Reader plan_poses(receiver_participant, Topic::kPlanPose);
  platform::Waiter waiter(receiver_participant);
  waiter.Attach(plan_poses);
  std::unordered_map<std::string, Headset*> by_device;
  for (Headset& hs : headsets) by_device[hs.device] = &hs;
  std::atomic<bool> stop{false};
  std::atomic<size_t> answered{0};
  std::thread receiver([&] {
    while (!stop.load()) {
      waiter.Wait(std::chrono::milliseconds(50));
      const int64_t now = platform::MonotonicNs();
      for (const platform::Envelope& e : plan_poses.Take(1024)) {
        auto it = by_device.find(e.device_id);
        v1::PlanPose p;
        if (it == by_device.end() || !p.ParseFromString(e.payload)) continue;
        Headset& hs = *it->second;
        auto step = hs.step_of_stamp.find(p.source_stamp_ns());
        if (step == hs.step_of_stamp.end() || hs.answered[step->second]) continue;
        hs.answered[step->second] = 1;
        hs.latency_ms.push_back(
            static_cast<double>(e.source_timestamp_ns - hs.sent_wall_ns[step->second].load()) *
            1e-6);
        hs.round_trip_ms.push_back(static_cast<double>(now - hs.sent_ns[step->second].load()) *
                                   1e-6);
        hs.latency_step.push_back(step->second);
        answered.fetch_add(1);
      }
    }
  });

  // Every walk starts at the same virtual time with the same pose period: the longest one
  // paces them all.
  const sim::Simulation& clock =
      std::max_element(headsets.begin(), headsets.end(), [](const Headset& a, const Headset& b) {
        return a.walk.steps.size() < b.walk.steps.size();
      })->walk;
  const size_t steps = clock.steps.size();
  size_t poses_sent = 0;
  const int64_t first_stamp = headsets.front().walk.steps.front().stamp_ns;
  const double walk_s = headsets.front().walk.duration_s;
  if (!o.json)
    std::printf(
        "floorpose bench daemon: %d headset(s) and daemon(s) on domain %u, plan %s\n"
        "  walk %.0f m in %.1f min each (%zu poses, %zu mesh deltas), rates x%g, played at "
        "%gx real time\n",
        o.headsets, domain, plan_path.c_str(), headsets.front().walk.length_m, walk_s / 60.0,
        headsets.front().walk.steps.size(), headsets.front().mesh_deltas, o.rate_scale, o.speed);
  std::fflush(stdout);
  auto wait_for = [](auto pred, std::chrono::seconds timeout) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (!pred() && std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    return pred();
  };
  auto t0 = std::chrono::steady_clock::now();
  const int64_t ten_minutes_ns = first_stamp + static_cast<int64_t>(600e9);
  bool sampled_10min = false;
  for (size_t k = 0; k < steps; ++k) {
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
      ++poses_sent;
      if (k == hs.walk.pick_step)
        hs.link->Send(Topic::kCommand,
                      ToWallPickCommand(hs.walk.pick, hs.walk.pick_height_m, frame, 1),
                      step.stamp_ns);
    }
    if (k == 0) {
      // The plan-pose writers keep only their latest pose for a reader they match late:
      // the walk goes on, from now, once every daemon has answered its first pose.
      if (!wait_for([&] { return answered.load() >= poses_sent; }, std::chrono::seconds(15)))
        spdlog::warn("the first poses were not all answered within 15 s");
      t0 = std::chrono::steady_clock::now();
    }
    if (!sampled_10min && stamp >= ten_minutes_ns) {
      for (Headset& hs : headsets) hs.at_10min = SampleProcess(hs.daemon->pid());
      sampled_10min = true;
    }
  }
  wait_for([&] { return answered.load() >= poses_sent; }, std::chrono::seconds(5));
  const double played_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (Headset& hs : headsets) {
    hs.at_end = SampleProcess(hs.daemon->pid());
    // The last status, for the store's size and the daemon's own counters.
    hs.link->WaitUntil(
        [&] {
          return hs.link->status && hs.link->status->counters().poses_in() >= hs.walk.steps.size();
        },
        std::chrono::seconds(3));
  }
  stop = true;
  waiter.Wake();
  receiver.join();
  bool clean = true;
  for (Headset& hs : headsets) {
    const auto code = hs.daemon->Terminate(std::chrono::seconds(5));
    clean = clean && code && *code == 0;
  }

  // Everything, all headsets together; memory and CPU per daemon (the worst, and the mean).
  std::vector<double> latency, round_trip, registrations;
  size_t dropped = 0, late = 0, wall_points = 0, meshes = 0;
  double rss_peak = 0, rss_10 = 0, rss_final = 0, cpu_s = 0;
  for (const Headset& hs : headsets) {
    latency.insert(latency.end(), hs.latency_ms.begin(), hs.latency_ms.end());
    round_trip.insert(round_trip.end(), hs.round_trip_ms.begin(), hs.round_trip_ms.end());
    dropped += hs.walk.steps.size() - hs.latency_ms.size();
    late += static_cast<size_t>(std::count_if(hs.round_trip_ms.begin(), hs.round_trip_ms.end(),
                                              [&](double ms) { return ms > o.late_ms; }));
    const std::vector<double> r = RegistrationTimes(hs.log_path);
    registrations.insert(registrations.end(), r.begin(), r.end());
    rss_peak = std::max(rss_peak, hs.at_end.hwm_mb);
    rss_10 = std::max(rss_10, sampled_10min ? hs.at_10min.rss_mb : 0.0);
    rss_final = std::max(rss_final, hs.at_end.rss_mb);
    cpu_s += hs.at_end.cpu_s / o.headsets;
    if (hs.link->status) {
      wall_points = std::max<size_t>(wall_points, hs.link->status->wall_points());
      meshes = std::max<size_t>(meshes, hs.link->status->live_meshes());
    }
  }
  if (!o.latency_csv.empty()) {
    std::ofstream csv(o.latency_csv);
    csv << "device,t_s,latency_ms,round_trip_ms,mesh_deltas_before\n";
    for (const Headset& hs : headsets)
      for (size_t i = 0; i < hs.latency_ms.size(); ++i) {
        const sim::SimulatedStep& step = hs.walk.steps[hs.latency_step[i]];
        csv << hs.device << ',' << static_cast<double>(step.stamp_ns - first_stamp) * 1e-9 << ','
            << hs.latency_ms[i] << ',' << hs.round_trip_ms[i] << ',' << step.meshes.size() << '\n';
      }
  }
  const double cpu_percent = 100.0 * cpu_s / walk_s;
  const double cpu_percent_played = 100.0 * cpu_s / played_s;

  if (o.json) {
    nlohmann::json j = {
        {"headsets", o.headsets},
        {"speed", o.speed},
        {"rate_scale", o.rate_scale},
        {"walk_s", walk_s},
        {"walk_m", headsets.front().walk.length_m},
        {"mesh_deltas", headsets.front().mesh_deltas},
        {"latency_ms_p50", Percentile(latency, 0.5)},
        {"latency_ms_p99", Percentile(latency, 0.99)},
        {"latency_ms_max", Max(latency)},
        {"round_trip_ms_p50", Percentile(round_trip, 0.5)},
        {"round_trip_ms_p99", Percentile(round_trip, 0.99)},
        {"round_trip_ms_max", Max(round_trip)},
        {"registrations", registrations.size()},
        {"registration_ms_p50", Percentile(registrations, 0.5)},
        {"registration_ms_p99", Percentile(registrations, 0.99)},
        {"registration_ms_max", Max(registrations)},
        {"rss_mb_peak", rss_peak},
        {"rss_mb_10min", sampled_10min ? nlohmann::json(rss_10) : nlohmann::json(nullptr)},
        {"rss_mb_final", rss_final},
        {"cpu_s_per_walk_minute", cpu_s / (walk_s / 60.0)},
        {"cpu_percent", cpu_percent},
        {"cpu_percent_played", cpu_percent_played},
        {"poses_in", poses_sent},
        {"poses_out", latency.size()},
        {"dropped", dropped},
        {"late", late},
        {"wall_points", wall_points},
        {"live_meshes", meshes},
        {"stopped_cleanly", clean},
    };
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf("  pose written to plan pose written      p50 %.2f  p99 %.2f  max %.2f ms\n",
                Percentile(latency, 0.5), Percentile(latency, 0.99), Max(latency));
    std::printf("  ...and back at the headset             p50 %.2f  p99 %.2f  max %.2f ms\n",
                Percentile(round_trip, 0.5), Percentile(round_trip, 0.99), Max(round_trip));
    std::printf(
        "  poses sent / answered                  %zu / %zu: %zu dropped, %zu late (> %g ms)\n",
        poses_sent, latency.size(), dropped, late, o.late_ms);
    std::printf("  registrations                          %zu: p50 %.1f  p99 %.1f  max %.1f ms\n",
                registrations.size(), Percentile(registrations, 0.5),
                Percentile(registrations, 0.99), Max(registrations));
    std::printf(
        "  CPU per daemon                         %.2f s per minute of walk: %.2f%% of a core at "
        "real time (%.1f%% while played)\n",
        cpu_s / (walk_s / 60.0), cpu_percent, cpu_percent_played);
    if (sampled_10min)
      std::printf(
          "  RSS per daemon (worst)                 peak %.1f MB, after 10 min %.1f MB, "
          "final %.1f MB\n",
          rss_peak, rss_10, rss_final);
    else
      std::printf("  RSS per daemon (worst)                 peak %.1f MB, final %.1f MB\n",
                  rss_peak, rss_final);
    std::printf("  wall store at the end                  %zu points in %zu meshes\n", wall_points,
                meshes);
    for (const Headset& hs : headsets)
      std::printf("  %-8s  cpu %.1f s  rss %.1f MB (peak %.1f)  answered %zu / %zu\n",
                  hs.device.c_str(), hs.at_end.cpu_s, hs.at_end.rss_mb, hs.at_end.hwm_mb,
                  hs.latency_ms.size(), hs.walk.steps.size());
    std::printf("  floorposed stopped                     %s\n", clean ? "cleanly" : "NOT cleanly");
  }
  if (o.logs.empty() && clean) fs::remove_all(tmp);
  return clean && dropped == 0 ? 0 : 1;
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
