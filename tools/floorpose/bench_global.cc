// `floorpose bench global`: the global search (core/global_search.h) on a plan: how long
// building its grids and searching take, and how often the best place is the true one.
//
// Each trial stands at a random place of the plan where walls are seen all around, casts
// 720 rays out to --range metres (a laser's view, walls occluding walls), adds 3 cm of
// noise, moves the hits into a random slam frame (any heading, any offset) and searches
// the whole plan at every heading.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "core/global_search.h"
#include "core/random.h"
#include "platform/floor_plan_io.h"
#include "tools/floorpose/commands.h"
#include "tools/lib/evaluation.h"

namespace floorpose::tools {
namespace {

struct BenchGlobalOptions {
  std::string plan;
  int trials = 20;
  uint64_t seed = 1;
  double range_m = 8.0;
  GlobalSearchOptions search;
  bool wall_headings = false;
  bool json = false;
};

// The nearest wall along a ray from p, within max_m.
std::optional<double> CastRay(const FloorPlan& plan, const Eigen::Vector2d& p,
                              const Eigen::Vector2d& dir, double max_m) {
  std::optional<double> best;
  for (const Segment& s : plan.segments) {
    const Eigen::Vector2d e = s.b - s.a, w = s.a - p;
    const double denom = dir.x() * e.y() - dir.y() * e.x();
    if (std::abs(denom) < 1e-12) continue;
    const double t = (w.x() * e.y() - w.y() * e.x()) / denom;      // along the ray
    const double u = (w.x() * dir.y() - w.y() * dir.x()) / denom;  // along the segment
    if (t > 0 && t <= max_m && u >= 0 && u <= 1 && (!best || t < *best)) best = t;
  }
  return best;
}

// A laser's view from `at` (plan frame): 720 rays out to range_m, each hit with 3 cm of
// noise, cast until one meets a wall within 0.5 m (too close, or inside one); empty when
// fewer than 600 rays hit a wall (outside the building, or cut short by a wall too close).
std::vector<Eigen::Vector2d> LaserView(const FloorPlan& plan, const Eigen::Vector2d& at,
                                       double range_m, SplitMix64& rng) {
  std::vector<Eigen::Vector2d> hits;
  for (int k = 0; k < 720; ++k) {
    const double a = k * M_PI / 360;
    const Eigen::Vector2d dir(std::cos(a), std::sin(a));
    if (const auto t = CastRay(plan, at, dir, range_m)) {
      if (*t < 0.5) break;
      hits.push_back(at + *t * dir + 0.03 * Eigen::Vector2d(rng.Gaussian(), rng.Gaussian()));
    }
  }
  if (hits.size() < 600) return {};
  return hits;
}

// How near the truth the best place must be to count as found: two search cells, at least
// 0.3 m (and within 2 degrees).
double FoundToleranceM(const GlobalSearch& search) {
  return std::max(0.3, 2 * search.grid().cell_m);
}

// What the trials measured.
struct BenchGlobalResult {
  double build_ms = 0;
  std::vector<double> times, rotations;  // per search: milliseconds, headings tried
  int found = 0, unique = 0;             // the best place right; clearly ahead of the next
};

void PrintBenchGlobal(bool json, const std::string& path, const FloorPlan& plan,
                      const GlobalSearch& search, const BenchGlobalResult& r) {
  const int n = static_cast<int>(r.times.size());
  if (json) {
    std::printf("%s\n", nlohmann::json{{"plan", path},
                                       {"segments", plan.segments.size()},
                                       {"cells", search.grid().size()},
                                       {"cell_m", search.grid().cell_m},
                                       {"build_ms", r.build_ms},
                                       {"memory_mb", search.MemoryBytes() / 1048576.0},
                                       {"trials", n},
                                       {"found", r.found},
                                       {"unique", r.unique},
                                       {"search_ms_p50", Percentile(r.times, 0.5)},
                                       {"search_ms_p99", Percentile(r.times, 0.99)},
                                       {"search_ms_max", Percentile(r.times, 1.0)},
                                       {"headings_p50", Percentile(r.rotations, 0.5)}}
                            .dump()
                            .c_str());
  } else {
    std::printf("%s: %zu walls, %zu cells of %.2f m, grids built in %.1f ms (%.1f MB)\n",
                path.c_str(), plan.segments.size(), search.grid().size(), search.grid().cell_m,
                r.build_ms, search.MemoryBytes() / 1048576.0);
    std::printf(
        "  %d searches over the whole plan and every heading: %.1f / %.1f / %.1f ms "
        "(p50 / p99 / max)\n",
        n, Percentile(r.times, 0.5), Percentile(r.times, 0.99), Percentile(r.times, 1.0));
    std::printf("  best place within %.1f m and 2 deg: %d of %d; clearly ahead of the next: %d\n",
                FoundToleranceM(search), r.found, n, r.unique);
  }
}

int RunBenchGlobal(const BenchGlobalOptions& o) {
  const std::string path = o.plan.empty() ? DefaultDemoPlan() : o.plan;
  const FloorPlanParse parse = platform::LoadFloorPlan(path);
  if (!parse.ok()) {
    spdlog::error("{}: {}", path, parse.error);
    return 1;
  }
  const FloorPlan& plan = parse.plan;
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const GlobalSearch search(plan, o.search);
  BenchGlobalResult r;
  r.build_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();

  SplitMix64 rng(o.seed);
  int tries = 0;
  while (static_cast<int>(r.times.size()) < o.trials && tries++ < 100 * o.trials) {
    const Eigen::Vector2d at(rng.Uniform(plan.min.x(), plan.max.x()),
                             rng.Uniform(plan.min.y(), plan.max.y()));
    std::vector<Eigen::Vector2d> hits = LaserView(plan, at, o.range_m, rng);
    if (hits.empty()) continue;
    const Se2 T_slam_plan{rng.Uniform(-M_PI, M_PI),
                          {rng.Uniform(-100, 100), rng.Uniform(-100, 100)}};
    for (Eigen::Vector2d& h : hits) h = T_slam_plan * h;
    GlobalSearchStats stats;
    const auto start = Clock::now();
    const std::vector<GlobalPlace> places = search.Search(
        hits, o.wall_headings ? search.WallHeadings(hits) : std::vector<double>{}, &stats);
    r.times.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
    r.rotations.push_back(static_cast<double>(stats.rotations));
    if (places.empty()) continue;
    const Se2 e = places[0].T_plan_slam * T_slam_plan;  // identity when right
    if ((e * at - at).norm() < FoundToleranceM(search) &&
        std::abs(WrapAngle(e.theta)) < 2 * M_PI / 180)
      ++r.found;
    if (places.size() < 2 || places[1].score < 0.9 * places[0].score) ++r.unique;
  }
  PrintBenchGlobal(o.json, path, plan, search, r);
  return r.times.empty() ? 1 : 0;
}

}  // namespace

Run AddBenchGlobalCommand(CLI::App& bench) {
  auto o = std::make_shared<BenchGlobalOptions>();
  CLI::App* app = bench.add_subcommand(
      "global", "the global search (no wall pick) on a plan: grid build, search time, hits");
  app->add_option("--plan", o->plan, "floor plan (default: the bundled office)");
  app->add_option("--trials", o->trials, "random places")->capture_default_str();
  app->add_option("--seed", o->seed, "seed")->capture_default_str();
  app->add_option("--range", o->range_m, "how far the simulated laser sees, metres")
      ->capture_default_str();
  app->add_option("--cell", o->search.cell_m, "search grid cell, metres")->capture_default_str();
  app->add_option("--places", o->search.places, "distinct places wanted")->capture_default_str();
  app->add_flag("--wall-headings", o->wall_headings,
                "try only the headings the walls' directions allow (GlobalSearch::WallHeadings)");
  app->add_flag("--json", o->json, "print one JSON object");
  return [o] { return RunBenchGlobal(*o); };
}

}  // namespace floorpose::tools
