// `floorpose simulate`: a simulated walk over a floor plan, written as a recording of what
// the headset would send (mesh deltas, poses, the wall pick) plus ground truth. Replay it
// with `floorpose replay`; the ground truth topics are skipped there.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <memory>

#include "platform/floor_plan_io.h"
#include "tools/floorpose/commands.h"
#include "tools/lib/simulate_recording.h"

namespace floorpose::tools {
namespace {

struct SimulateOptions {
  std::string plan;
  std::string scenario = "office";
  std::string trajectory;
  std::string waypoints, walk;
  std::string out;
  std::string frame = "unity";
  bool no_mesh = false;
  double pace_mps = 0.0;
  sim::SimulatorOptions sim;
  SimulateRecordingOptions recording;
  bool seed_given = false, scenario_given = false;
};

int RunSimulate(SimulateOptions o) {
  const auto start = std::chrono::steady_clock::now();
  FloorPlanParse plan = platform::LoadFloorPlan(o.plan);
  if (!plan.ok()) {
    spdlog::error("{}", plan.error);
    return 1;
  }
  o.sim.scenario = *sim::ParseScenario(o.scenario);  // checked by CLI11
  o.sim.mesh = !o.no_mesh;
  o.recording.frame = *ParseHeadsetFrame(o.frame);
  std::vector<sim::TimedPose> trajectory;
  std::string error;
  if (!o.trajectory.empty()) {
    if (!ReadTumTrajectory(o.trajectory, &trajectory, &error)) {
      spdlog::error("{}", error);
      return 1;
    }
    if (o.pace_mps > 0) PaceTrajectory(&trajectory, o.pace_mps, M_PI / 4);
  } else if (!o.waypoints.empty()) {
    WaypointWalks walks;
    if (!ReadWaypoints(o.waypoints, &walks, &error)) {
      spdlog::error("{}", error);
      return 1;
    }
    const auto it = walks.walks.find(o.walk);
    if (it == walks.walks.end() || it->second.size() < 2) {
      spdlog::error("{}: {} (of {} walks)", o.waypoints,
                    it == walks.walks.end() ? "no walk '" + o.walk + "'"
                                            : "walk '" + o.walk + "' has fewer than two waypoints",
                    walks.ids.size());
      return 1;
    }
    // The walk as eval-suite --waypoints walks it, unless told otherwise.
    const sim::SimulatorOptions suite = WaypointWalkSimulator(o.walk);
    if (!o.seed_given) o.sim.seed = suite.seed;
    if (!o.scenario_given) {
      o.sim.scenario = suite.scenario;
      o.scenario = sim::ToString(suite.scenario);
    }
    plan.plan.id = WaypointFloorName(o.waypoints);
    trajectory = sim::WalkWaypoints(it->second, o.sim);
  }
  SimulateRecordingResult result;
  if (!SimulateToRecording(plan.plan, o.sim, trajectory.empty() ? nullptr : &trajectory,
                           o.recording, o.out, &result, &error)) {
    spdlog::error("{}", error);
    return 1;
  }
  // Where the plan as drawn is not the building (doors, scaled), the daemon is given it.
  std::string drawn_path;
  if (PlanDiffersFromInput(result.simulation, plan.plan)) {
    drawn_path = o.out + ".plan.geojson";
    if (!WriteDrawnPlan(result.simulation, drawn_path, &error)) {
      spdlog::error("{}", error);
      return 1;
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const sim::Simulation& s = result.simulation;
  const sim::DriftStats& d = result.drift;
  std::printf("floorpose simulate: %s, scenario %s, seed %lu -> %s\n", plan.plan.id.c_str(),
              o.scenario.c_str(), static_cast<unsigned long>(o.sim.seed), o.out.c_str());
  std::printf("  %s\n", s.description.c_str());
  std::printf("  walk                           %.0f m in %.0f s, %zu poses\n", s.length_m,
              s.duration_s, s.steps.size());
  std::printf("  meshes added/updated/removed   %zu / %zu / %zu (%zu vertices, %zu triangles)\n",
              s.counts.added, s.counts.updated, s.counts.removed, s.counts.vertices,
              s.counts.triangles);
  std::printf(
      "  SLAM drift                     %.2f m at the end (%.2f%% of the walk); best fit "
      "mean %.2f m, max %.2f m\n",
      d.end_error_m, d.length_m > 0 ? 100.0 * d.end_error_m / d.length_m : 0.0, d.best_fit_mean_m,
      d.best_fit_max_m);
  std::printf("  recording                      %zu records, %.1f MB, in %.1f s\n", result.records,
              static_cast<double>(result.bytes) / 1e6, seconds);
  if (!drawn_path.empty()) std::printf("  plan as drawn (evaluate on it) %s\n", drawn_path.c_str());
  return 0;
}

}  // namespace

Run AddSimulateCommand(CLI::App& app) {
  auto o = std::make_shared<SimulateOptions>();
  app.add_option("--plan", o->plan, "floor plan (.geojson or .txt)")->required();
  auto* seed = app.add_option("--seed", o->sim.seed,
                              "simulation seed (with --waypoints: a hash of the walk id, as "
                              "eval-suite --waypoints draws it)")
                   ->capture_default_str();
  auto* scenario =
      app.add_option("--scenario", o->scenario,
                     "corridor, office, glass, hall, mismatch; and reality unlike the plan: doors "
                     "(drawn closed), stale (walls gone, new, moved), scaled (plan 1-2% off in "
                     "scale, skewed), relocalize (tracking lost, the SLAM frame jumps). Where the "
                     "plan as drawn differs (doors, scaled) it is written beside --out (with "
                     "--waypoints: corridor, as eval-suite --waypoints walks them)")
          ->check(CLI::IsMember(sim::ScenarioNames()))
          ->capture_default_str();
  auto* trajectory =
      app.add_option("--trajectory", o->trajectory,
                     "walk this TUM trajectory on the plan ('timestamp x y z qx qy qz qw')");
  auto* waypoints =
      app.add_option("--waypoints", o->waypoints,
                     "walk one walk of this waypoint CSV ('walk,t_ms,x_m,y_m', plan frame) at "
                     "its own timing, straight from waypoint to waypoint, as eval-suite "
                     "--waypoints walks it (the plan named after the CSV's folder)")
          ->excludes(trajectory);
  app.add_option("--walk", o->walk, "the walk id in --waypoints")->needs(waypoints);
  waypoints->needs("--walk");
  app.add_option("--pace", o->pace_mps,
                 "re-time the trajectory at this walking speed, m/s (for logs whose "
                 "timestamps are line numbers, such as CARMEN csail's ground truth)")
      ->check(CLI::Range(0.05, 10.0));
  app.add_option("--out", o->out, "recording file to write")->required();
  app.add_option("--length", o->sim.target_length_m, "walk length, metres")->capture_default_str();
  app.add_option("--max-duration", o->sim.max_duration_s, "walk at most this long, seconds")
      ->capture_default_str();
  app.add_option("--drift-scale", o->sim.drift_scale, "SLAM drift, times the nominal")
      ->capture_default_str();
  app.add_option("--device", o->recording.device_id, "envelope device id")->capture_default_str();
  app.add_option("--floor", o->recording.floor, "floor id of the ground truth")
      ->capture_default_str();
  app.add_option("--frame", o->frame, "headset convention: unity (Y up, left-handed) or zup")
      ->check(CLI::IsMember({"unity", "zup"}))
      ->capture_default_str();
  app.add_option("--stairs-at", o->recording.stairs_at,
                 "climb a flight of stairs this far through the walk (0..1; 0: one floor) onto "
                 "a floor of the same layout, as in a .floors set listing the plan twice")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--floor-height", o->recording.floor_height_m,
                 "height of the flight of stairs, metres")
      ->check(CLI::Range(1.0, 20.0))
      ->capture_default_str();
  app.add_option("--upper-floor", o->recording.upper_floor, "floor id at the top of the stairs")
      ->capture_default_str();
  app.add_flag("--no-mesh", o->no_mesh, "poses and ground truth only");
  app.add_flag(
      "--kidnap",
      [o](int64_t) {
        o->sim.kidnap_m = 10.0;
        o->sim.kidnap_rad = M_PI / 2;
      },
      "write a wrong wall pick: 10 m and 90 degrees off at the wearer");
  return [o, seed, scenario] {
    o->seed_given = seed->count() > 0;
    o->scenario_given = scenario->count() > 0;
    return RunSimulate(*o);
  };
}

}  // namespace floorpose::tools
