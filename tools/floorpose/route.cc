// `floorpose route`: the route the daemon would answer, offline, from a plan file.
// `floorpose bench route`: how long building the grid and answering routes take.
#include <chrono>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/random.h"
#include "core/route_planner.h"
#include "platform/floor_plan_io.h"
#include "tools/floorpose/commands.h"

namespace floorpose::tools {
namespace {

using Clock = std::chrono::steady_clock;

struct RouteCommandOptions {
  std::string plan;
  std::vector<double> from, to;
  RouteOptions route;
  bool json = false;
  bool way_out = false;
  int routes = 200;  // bench: random pairs
  uint64_t seed = 1;
};

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// The plan's route grid, and how long it took to build; null (after a message) when the
// plan does not load.
struct LoadedPlanner {
  std::unique_ptr<RoutePlanner> planner;
  double build_ms = 0;
};
LoadedPlanner LoadPlanner(const RouteCommandOptions& o) {
  const FloorPlanParse parse = platform::LoadFloorPlan(o.plan);
  if (!parse.ok()) {
    std::fprintf(stderr, "floorpose: %s: %s\n", o.plan.c_str(), parse.error.c_str());
    return {};
  }
  const auto built = Clock::now();
  LoadedPlanner out;
  out.planner = std::make_unique<RoutePlanner>(parse.plan, o.route);
  out.build_ms = MsSince(built);
  return out;
}

int RunRoute(const RouteCommandOptions& o) {
  const auto [loaded, build_ms] = LoadPlanner(o);
  if (!loaded) return 1;
  const RoutePlanner& planner = *loaded;
  const auto asked = Clock::now();
  const Eigen::Vector2d from(o.from[0], o.from[1]);
  const Route route = o.way_out ? planner.WayOut(from) : planner.Plan(from, {o.to[0], o.to[1]});
  const double route_ms = MsSince(asked);
  if (o.json) {
    nlohmann::json j;
    if (route.ok()) {
      j["length_m"] = route.length_m;
      j["path"] = nlohmann::json::array();
      for (const Eigen::Vector2d& p : route.path) j["path"].push_back({p.x(), p.y()});
      j["start_moved_m"] = route.start_moved_m;
      j["goal_moved_m"] = route.goal_moved_m;
    } else {
      j["error"] = route.error;
    }
    j["time_ms"] = route_ms;
    j["grid_build_ms"] = build_ms;
    std::printf("%s\n", j.dump().c_str());
  } else if (route.ok()) {
    std::printf("%.2f m in %zu legs (%.1f ms; grid %.0f ms)\n", route.length_m,
                route.path.size() - 1, route_ms, build_ms);
    for (const Eigen::Vector2d& p : route.path) std::printf("  %.2f %.2f\n", p.x(), p.y());
    if (route.start_moved_m > 0)
      std::printf("start is %.2f m from the first clear point\n", route.start_moved_m);
    if (route.goal_moved_m > 0)
      std::printf("ends %.2f m short of the destination, which is too close to a wall\n",
                  route.goal_moved_m);
  } else {
    std::fprintf(stderr, "floorpose: %s\n", route.error.c_str());
  }
  return route.ok() ? 0 : 1;
}

int RunBenchRoute(const RouteCommandOptions& o) {
  const auto [loaded, build_ms] = LoadPlanner(o);
  if (!loaded) return 1;
  const RoutePlanner& planner = *loaded;
  std::vector<int> passable;
  for (int cell = 0; cell < static_cast<int>(planner.grid().size()); ++cell)
    if (planner.Passable(cell)) passable.push_back(cell);
  if (passable.empty()) {
    std::fprintf(stderr, "floorpose: no free space on %s\n", o.plan.c_str());
    return 1;
  }
  SplitMix64 rng(o.seed);
  auto draw = [&] {
    const auto i = static_cast<size_t>(rng.Uniform(0, static_cast<double>(passable.size())));
    return planner.grid().CellCentre(passable[std::min(i, passable.size() - 1)]);
  };
  std::vector<double> ms, lengths;
  int refused = 0;
  for (int i = 0; i < o.routes; ++i) {
    const Eigen::Vector2d a = draw(), b = draw();
    const auto start = Clock::now();
    const Route route = planner.Plan(a, b);
    const double t = MsSince(start);
    if (!route.ok()) {
      ++refused;
      continue;
    }
    ms.push_back(t);
    lengths.push_back(route.length_m);
  }
  std::sort(ms.begin(), ms.end());
  auto at = [&](double q) {
    return ms.empty() ? 0.0 : ms[std::min(ms.size() - 1, static_cast<size_t>(q * ms.size()))];
  };
  const double longest = lengths.empty() ? 0 : *std::max_element(lengths.begin(), lengths.end());
  if (o.json) {
    nlohmann::json j{{"plan", o.plan},
                     {"cells", planner.grid().size()},
                     {"cell_m", planner.grid().cell_m},
                     {"grid_build_ms", build_ms},
                     {"routes", ms.size()},
                     {"refused", refused},
                     {"route_ms_p50", at(0.5)},
                     {"route_ms_p99", at(0.99)},
                     {"route_ms_max", ms.empty() ? 0.0 : ms.back()},
                     {"longest_route_m", longest}};
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf("%s: grid %d x %d cells of %.2f m, built in %.1f ms\n", o.plan.c_str(),
                planner.grid().nx, planner.grid().ny, planner.grid().cell_m, build_ms);
    std::printf("%zu routes (longest %.1f m), %d refused: p50 %.2f ms, p99 %.2f ms, max %.2f ms\n",
                ms.size(), longest, refused, at(0.5), at(0.99), ms.empty() ? 0.0 : ms.back());
  }
  return 0;
}

void AddPlannerOptions(CLI::App& app, RouteCommandOptions& o) {
  app.add_option("--plan", o.plan, "floor plan (.geojson, .txt or raster .yaml)")->required();
  app.add_option("--radius", o.route.body_radius_m,
                 "body radius: the route keeps this far from walls, metres")
      ->capture_default_str();
  app.add_option("--cell", o.route.cell_m, "grid cell, metres")->capture_default_str();
  app.add_flag("--json", o.json, "one JSON object");
}

}  // namespace

Run AddRouteCommand(CLI::App& app) {
  auto o = std::make_shared<RouteCommandOptions>();
  AddPlannerOptions(app, *o);
  app.add_option("--from", o->from, "start X,Y on the plan, metres")
      ->required()
      ->delimiter(',')
      ->expected(2);
  CLI::Option* to = app.add_option("--to", o->to, "destination X,Y on the plan, metres")
                        ->delimiter(',')
                        ->expected(2);
  CLI::Option* out = app.add_flag(
      "--way-out", o->way_out, "to the nearest exit by route (the plan's stairs when it has none)");
  to->excludes(out);
  app.callback([to, out] {
    if (!to->count() && !out->count()) throw CLI::ValidationError("--to or --way-out is required");
  });
  return [o] { return RunRoute(*o); };
}

Run AddBenchRouteCommand(CLI::App& bench) {
  auto o = std::make_shared<RouteCommandOptions>();
  CLI::App* sub = bench.add_subcommand(
      "route", "time the route grid's build and routes between random free points of a plan");
  AddPlannerOptions(*sub, *o);
  sub->add_option("--routes", o->routes, "random pairs")->capture_default_str();
  sub->add_option("--seed", o->seed, "for the pairs")->capture_default_str();
  return [o] { return RunBenchRoute(*o); };
}

}  // namespace floorpose::tools
