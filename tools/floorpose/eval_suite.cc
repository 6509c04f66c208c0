// `floorpose eval-suite`: every plan x scenario x seed simulated once, then evaluated with
// every method and both baselines; a markdown table like thesis table 7.10 and JSON.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "core/sim/simulator.h"
#include "platform/config.h"
#include "platform/floor_plan_io.h"
#include "tools/floorpose/commands.h"
#include "tools/floorpose/eval_real.h"
#include "tools/lib/calibration.h"
#include "tools/lib/evaluation.h"
#include "tools/lib/progress.h"
#include "tools/lib/simulate_recording.h"

namespace floorpose::tools {
namespace {

namespace fs = std::filesystem;

struct SuiteOptions {
  std::vector<std::string> plans;  // files or directories (searched for *.geojson)
  int seeds = 3;
  std::string out;
  std::vector<std::string> scenarios = sim::ScenarioNames();
  // The daemon's default first: the reliability tables and the SVGs are of the first.
  std::vector<std::string> methods = {"mcl", "none", "best-fit"};
  double length_m = 0;  // 0: the simulator's default
  int jobs = 0;
  std::string config;  // floorposed configuration to evaluate with
  int first_seed = 1;
  bool no_pick = false;                // drop the walks' wall picks: the daemon searches the plan
  bool kidnap = false;                 // wrong picks (simulate --kidnap), searched and checked
  RealSuiteOptions carmen, waypoints;  // real data instead of simulated walks
};

struct SuiteRun {
  std::string plan_path, plan_id, scenario;
  uint64_t seed;
  std::string recording;
  std::string drawn_plan;  // where the plan as drawn differs (doors, scaled): its file
};

std::vector<std::string> PlanFiles(const std::vector<std::string>& inputs) {
  std::vector<std::string> out;
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (fs::is_directory(in, ec)) {
      for (const auto& e : fs::recursive_directory_iterator(in, ec))
        if (e.is_regular_file() && e.path().extension() == ".geojson") out.push_back(e.path());
    } else {
      out.push_back(in);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Seconds with one decimal, or "never" (infinite).
std::string Seconds(double s) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(1);
  if (std::isfinite(s))
    out << s;
  else
    out << "never";
  return out.str();
}

// Issue 7's placement figures (runs without a pick, one method), per scenario. The search
// ends at the first pose flagged RELIABLE: within 1 m, the wearer is placed; more than
// 1 m off, the search flagged a wrong place RELIABLE. A run never flagged RELIABLE is
// never placed (its time counts as infinite in the median). After the placement the
// tracker runs as after a pick; its RELIABLE poses more than 1 m off are counted apart.
std::string PlacementTable(const std::vector<EvalReport>& reports, const std::string& method,
                           const std::vector<std::string>& scenarios) {
  std::ostringstream md;
  md.setf(std::ios::fixed);
  md.precision(1);
  md << "\nPlacement without a pick (" << method
     << "; the search ends at the first RELIABLE pose):\n\n"
        "| scenario | runs | placed within 1 m | placed more than 1 m off | never placed | "
        "seconds to placed, median | of walking (from the first step), median | slowest | "
        "RELIABLE poses > 1 m off after placement (runs) "
        "|\n|---|---|---|---|---|---|---|---|---|\n";
  auto row = [&](const std::string& name, const std::string& scenario) {
    size_t runs = 0, placed = 0, wrong = 0, false_poses = 0, false_runs = 0;
    std::vector<double> times, walking;
    for (const EvalReport& r : reports) {
      if (r.method != method || (!scenario.empty() && r.scenario != scenario)) continue;
      ++runs;
      const auto first = std::find_if(r.track.begin(), r.track.end(),
                                      [](const EvalPose& p) { return p.reliable; });
      if (first == r.track.end() || first->error_m > 1.0) {
        wrong += first != r.track.end();
        times.push_back(std::numeric_limits<double>::infinity());
        walking.push_back(std::numeric_limits<double>::infinity());
        continue;
      }
      ++placed;
      times.push_back(r.time_to_first_reliable_s);
      walking.push_back(std::max(0.0, r.time_to_first_reliable_s - std::max(0.0, r.first_step_s)));
      false_poses += r.false_reliable_poses;
      false_runs += r.false_reliable_poses > 0;
    }
    if (!runs) return;
    std::sort(times.begin(), times.end());
    std::sort(walking.begin(), walking.end());
    md << "| " << name << " | " << runs << " | " << placed << " (" << 100.0 * placed / runs
       << "%) | " << wrong << " | " << runs - placed - wrong << " | "
       << Seconds(times[(times.size() - 1) / 2]) << " | "
       << Seconds(walking[(walking.size() - 1) / 2]) << " | " << Seconds(times.back()) << " | "
       << false_poses << " (" << false_runs << ") |\n";
  };
  for (const std::string& scenario : scenarios) row(scenario, scenario);
  row("all", "");
  return md.str();
}

// The kidnap figures (wrong picks, 10 m and 90 degrees off), per scenario: runs flagged
// UNRELIABLE within 5 s of the pick, runs flagged RELIABLE within 1 m within
// kBackAfterKidnapS of it (recovered), runs that did both (issue 43's target), the median
// time to recovered, and RELIABLE poses more than 1 m off: before the run recovered (a
// wrong place trusted) and in all.
std::string KidnapTable(const std::vector<EvalReport>& reports, const std::string& method,
                        const std::vector<std::string>& scenarios) {
  std::ostringstream md;
  md.setf(std::ios::fixed);
  md.precision(1);
  md << "\nKidnapped (" << method
     << "; a wall pick 10 m and 90 degrees off, times from the pick):\n\n"
        "| scenario | runs | UNRELIABLE within 5 s | recovered within "
     << static_cast<int>(kBackAfterKidnapS)
     << " s | both | seconds to recovered, median | slowest | RELIABLE poses > 1 m off before "
        "recovered (runs) | RELIABLE poses > 1 m off in all (runs) |\n"
        "|---|---|---|---|---|---|---|---|---|\n";
  auto row = [&](const std::string& name, const std::string& scenario) {
    size_t runs = 0, flagged = 0, recovered = 0, both = 0, false_poses = 0, false_runs = 0;
    size_t trusted_wrong = 0, trusted_wrong_runs = 0;
    std::vector<double> times;
    for (const EvalReport& r : reports) {
      if (r.method != method || (!scenario.empty() && r.scenario != scenario)) continue;
      ++runs;
      const bool f = r.time_to_unreliable_s >= 0 && r.time_to_unreliable_s <= 5.0;
      const bool rec = r.time_to_recovered_s >= 0 && r.time_to_recovered_s <= kBackAfterKidnapS;
      flagged += f;
      recovered += rec;
      both += f && rec;
      times.push_back(r.time_to_recovered_s >= 0 ? r.time_to_recovered_s
                                                 : std::numeric_limits<double>::infinity());
      false_poses += r.false_reliable_poses;
      false_runs += r.false_reliable_poses > 0;
      trusted_wrong += r.false_reliable_before_recovered;
      trusted_wrong_runs += r.false_reliable_before_recovered > 0;
    }
    if (!runs) return;
    std::sort(times.begin(), times.end());
    md << "| " << name << " | " << runs << " | " << flagged << " (" << 100.0 * flagged / runs
       << "%) | " << recovered << " (" << 100.0 * recovered / runs << "%) | " << both << " ("
       << 100.0 * both / runs << "%) | " << Seconds(times[(times.size() - 1) / 2]) << " | "
       << Seconds(times.back()) << " | " << trusted_wrong << " (" << trusted_wrong_runs << ") | "
       << false_poses << " (" << false_runs << ") |\n";
  };
  for (const std::string& scenario : scenarios) row(scenario, scenario);
  row("all", "");
  return md.str();
}

// Issue 43's figures after a loss of tracking (`relocalize`, a pick's runs or none), per
// scenario that has losses: RELIABLE within 1 m again within kBackAfterLossS of the first
// pose after each loss (of the losses followed that long or back before), the median and
// slowest time to it, and RELIABLE poses more than 1 m off before it.
std::string LossTable(const std::vector<EvalReport>& reports, const std::string& method,
                      const std::vector<std::string>& scenarios) {
  std::ostringstream md;
  md.setf(std::ios::fixed);
  md.precision(1);
  md << "\nAfter a loss of tracking (" << method << "; times from the first pose after it):\n\n"
     << "| scenario | runs | losses | followed " << static_cast<int>(kBackAfterLossS)
     << " s or back before | back within 1 m and RELIABLE within "
     << static_cast<int>(kBackAfterLossS)
     << " s | seconds to back, median | slowest | RELIABLE poses > 1 m off before back "
        "(losses) |\n|---|---|---|---|---|---|---|---|\n";
  bool any = false;
  auto row = [&](const std::string& name, const std::string& scenario) {
    size_t runs = 0, losses = 0, timed = 0, back = 0, false_poses = 0, false_losses = 0;
    std::vector<double> times;
    for (const EvalReport& r : reports) {
      if (r.method != method || (!scenario.empty() && r.scenario != scenario)) continue;
      if (r.losses.empty()) continue;
      ++runs;
      losses += r.losses.size();
      const LossCounts c = CountLosses(r.losses);
      timed += c.timed;
      back += c.back;
      false_poses += c.false_reliable;
      for (const LossScore& l : r.losses) {
        false_losses += l.false_reliable > 0;
        if (l.timed())
          times.push_back(l.back_s >= 0 ? l.back_s : std::numeric_limits<double>::infinity());
      }
    }
    if (!losses) return;
    any = true;
    std::sort(times.begin(), times.end());
    md << "| " << name << " | " << runs << " | " << losses << " | " << timed << " | " << back
       << " (" << (timed ? 100.0 * back / timed : 0.0) << "%) | "
       << (times.empty() ? "-" : Seconds(times[(times.size() - 1) / 2])) << " | "
       << (times.empty() ? "-" : Seconds(times.back())) << " | " << false_poses << " ("
       << false_losses << ") |\n";
  };
  for (const std::string& scenario : scenarios) row(scenario, scenario);
  row("all", "");
  return any ? md.str() : std::string();
}

// Every plan x scenario x seed, and where its recording goes.
std::vector<SuiteRun> PlanRuns(const SuiteOptions& o, const std::vector<std::string>& plans) {
  std::vector<SuiteRun> runs;
  for (const std::string& plan : plans)
    for (const std::string& scenario : o.scenarios)
      for (int seed = o.first_seed; seed < o.first_seed + o.seeds; ++seed) {
        const std::string id = fs::path(plan).stem().string();
        runs.push_back({plan,
                        id,
                        scenario,
                        static_cast<uint64_t>(seed),
                        (fs::path(o.out) / "recordings" /
                         (id + "_" + scenario + "_" + std::to_string(seed) + ".rec"))
                            .string(),
                        {}});
      }
  return runs;
}

// Simulates a run to its recording, and writes its plan as drawn where that differs from
// the input (doors, scaled); *plan_path is the plan the daemon is given. False: why, logged.
bool SimulateRun(const SuiteOptions& o, const FloorPlan& plan, SuiteRun* run,
                 std::string* plan_path) {
  sim::SimulatorOptions sim;
  sim.seed = run->seed;
  sim.scenario = *sim::ParseScenario(run->scenario);
  if (o.length_m > 0) sim.target_length_m = o.length_m;
  if (o.kidnap) {
    sim.kidnap_m = 10.0;
    sim.kidnap_rad = M_PI / 2;
  }
  SimulateRecordingResult simulated;
  std::string error;
  if (!SimulateToRecording(plan, sim, nullptr, {}, run->recording, &simulated, &error)) {
    spdlog::error("{}: {}", run->recording, error);
    return false;
  }
  *plan_path = run->plan_path;
  if (!PlanDiffersFromInput(simulated.simulation, plan)) return true;
  run->drawn_plan =
      (fs::path(o.out) / "plans" / (fs::path(run->recording).stem().string() + ".geojson"))
          .string();
  if (!WriteDrawnPlan(simulated.simulation, run->drawn_plan, &error)) {
    spdlog::error("{}", error);
    return false;
  }
  *plan_path = run->drawn_plan;
  return true;
}

// Evaluates a run's recording by one method. False: why, logged.
bool EvaluateRun(const v1::FloorposedConfig& base_config, const SuiteOptions& o,
                 const SuiteRun& run, const std::string& plan_path, const std::string& method,
                 EvalReport* report) {
  v1::FloorposedConfig config = base_config;
  config.set_plan_path(plan_path);
  config.set_log_level("warn");
  const Baseline baseline = method == "none"       ? Baseline::kNoAlgorithm
                            : method == "best-fit" ? Baseline::kBestFit
                                                   : Baseline::kNone;
  std::string error;
  if (!Evaluate(config, run.recording, baseline, report, &error, nullptr, o.no_pick)) {
    spdlog::error("{} {}: {}", run.recording, method, error);
    return false;
  }
  report->plan_id = run.plan_id;
  report->split = SimulatedSplit(run.seed);
  return true;
}

// The runs' mean errors by plan and scenario and method, and the runs by method.
struct Grouped {
  std::map<std::pair<std::string, std::string>, std::map<std::string, std::vector<double>>> cell;
  std::map<std::string, std::vector<const EvalReport*>> by_method;
};

// Per plan and scenario, the mean error over seeds per method (thesis table 7.10), then
// per method over everything.
void WriteErrorTables(const Grouped& g, const SuiteOptions& o, std::ostringstream& md) {
  md << "| plan | scenario |";
  for (const std::string& m : o.methods) md << " " << m << " |";
  md << "\n|---|---|";
  for (size_t i = 0; i < o.methods.size(); ++i) md << "---|";
  md << "\n";
  for (const auto& [key, methods] : g.cell) {
    md << "| " << key.first << " | " << key.second << " |";
    for (const std::string& m : o.methods) {
      auto it = methods.find(m);
      if (it == methods.end() || it->second.empty()) {
        md << " - |";
        continue;
      }
      md << " " << Mean(it->second) << " |";
    }
    md << "\n";
  }
  md << "\nMean error in metres over " << o.seeds
     << " seeds. Per method over all runs:\n\n"
        "| method | runs | mean error | p95 error | max error | final error | marker error | "
        "runs diverged (> 5 m) | reliable | reliable within 1 m | update ms (median) |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& m : o.methods) {
    const auto found = g.by_method.find(m);
    if (found == g.by_method.end() || found->second.empty()) continue;
    const auto& rs = found->second;
    double mean = 0, p95 = 0, mx = 0, fin = 0, marker = 0, rel = 0, prec = 0, reg = 0;
    size_t diverged = 0;
    for (const EvalReport* r : rs) {
      mean += r->mean_error_m;
      p95 += r->p95_error_m;
      mx = std::max(mx, r->max_error_m);
      fin += r->final_error_m;
      marker += r->marker_mean_error_m;
      rel += r->reliable_fraction;
      prec += r->reliable_precision_1m;
      reg += r->reg_time_ms_median;
      diverged += r->divergences > 0;
    }
    const double n = static_cast<double>(rs.size());
    md << "| " << m << " | " << rs.size() << " | " << mean / n << " | " << p95 / n << " | " << mx
       << " | " << fin / n << " | " << marker / n << " | " << diverged << " | " << 100 * rel / n
       << "% | " << 100 * prec / n << "% | " << reg / n << " |\n";
  }
}

// The Tracking issue's targets (first method): per cell (plan and scenario), the mean
// over seeds against 0.3 m (corridor, hall) or 0.6 m, and against best-fit + 0.1 m; per
// run, the max against 1.5 or 3 m, and divergences.
void WriteTargetsTable(const std::vector<EvalReport>& reports, const Grouped& g,
                       const SuiteOptions& o, std::ostringstream& md) {
  const std::string& first = o.methods.front();
  // over seeds against 0.3 m (corridor, hall) or 0.6 m, and against best-fit + 0.1 m;
  // per run, the max against 1.5 or 3 m, and divergences.
  md << "\nAgainst the Tracking targets (" << first
     << "; mean <= 0.3 m and max <= 1.5 m in corridor and hall, else 0.6 and 3 m):\n\n"
        "| scenario | mean | worst cell | cells above the mean target | runs above the max "
        "target | runs diverged | cells above best-fit + 0.1 m | from the first registration: "
        "cells above the mean target, runs above the max target |\n"
        "|---|---|---|---|---|---|---|---|\n";
  for (const std::string& scenario : o.scenarios) {
    const bool strict = scenario == "corridor" || scenario == "hall";
    const double mean_target = strict ? 0.3 : 0.6, max_target = strict ? 1.5 : 3.0;
    double sum = 0, worst = 0;
    size_t cells = 0, above = 0, above_best_fit = 0, above_max = 0, diverged = 0;
    for (const auto& [key, methods] : g.cell) {
      if (key.second != scenario) continue;
      const auto mean_of = [&](const std::string& m) {
        auto it = methods.find(m);
        return it == methods.end() || it->second.empty() ? -1.0 : Mean(it->second);
      };
      const double m = mean_of(first), best_fit = mean_of("best-fit");
      if (m < 0) continue;
      ++cells;
      sum += m;
      worst = std::max(worst, m);
      above += m > mean_target;
      above_best_fit += best_fit >= 0 && m > best_fit + 0.1;
    }
    // From the first registration on: what the tracker does once walls are in view, without
    // the pick's own error before it.
    std::map<std::string, std::vector<double>> settled;
    size_t settled_above_max = 0;
    for (const EvalReport& r : reports) {
      if (r.method != first || r.scenario != scenario) continue;
      above_max += r.max_error_m > max_target;
      diverged += r.divergences > 0;
      if (r.first_fix_s < 0) continue;
      settled[r.plan_id].push_back(r.settled_mean_error_m);
      settled_above_max += r.settled_max_error_m > max_target;
    }
    size_t settled_above = 0;
    for (const auto& [plan, means] : settled) settled_above += Mean(means) > mean_target;
    if (!cells) continue;
    md << "| " << scenario << " | " << sum / static_cast<double>(cells) << " | " << worst << " | "
       << above << " of " << cells << " | " << above_max << " | " << diverged << " | "
       << (g.by_method.count("best-fit") ? std::to_string(above_best_fit) : std::string("-"))
       << " | " << settled_above << " of " << settled.size() << ", " << settled_above_max << " |\n";
  }
}

// Reliability (first method): does RELIABLE mean within 1 m, per scenario; the placement,
// kidnap and loss tables; how calibrated the published probability is (*curve), and its
// Brier score.
void WriteReliabilityTables(const std::vector<EvalReport>& reports, const SuiteOptions& o,
                            std::ostringstream& md, std::vector<CalibrationBin>* curve) {
  const std::string& first = o.methods.front();
  md << "\nReliability (" << first
     << "): poses flagged RELIABLE, and the share of those within 1 m, per scenario:\n\n"
        "| scenario | poses | reliable | reliable within 1 m | all within 1 m "
        "|\n|---|---|---|---|---|\n";
  std::vector<double> predicted;
  std::vector<bool> within;
  double brier = 0;  // EvalReport::brier, pooled over the poses
  for (const std::string& scenario : o.scenarios) {
    size_t n = 0, reliable = 0, reliable_ok = 0, ok = 0;
    for (const EvalReport& r : reports) {
      if (r.method != first || r.scenario != scenario) continue;
      brier += r.brier * static_cast<double>(r.track.size());
      for (const EvalPose& p : r.track) {
        ++n;
        ok += p.error_m <= 1.0;
        reliable += p.reliable;
        reliable_ok += p.reliable && p.error_m <= 1.0;
        predicted.push_back(p.probability);
        within.push_back(p.error_m <= 1.0);
      }
    }
    if (!n) continue;
    md << "| " << scenario << " | " << n << " | " << 100.0 * reliable / n << "% | "
       << (reliable ? 100.0 * reliable_ok / reliable : 0.0) << "% | " << 100.0 * ok / n << "% |\n";
  }
  if (o.no_pick) md << PlacementTable(reports, first, o.scenarios);
  if (o.kidnap) md << KidnapTable(reports, first, o.scenarios);
  md << LossTable(reports, first, o.scenarios);
  *curve = CalibrationCurve(predicted, within);
  md << "\nCalibration of the published probability (" << first << ", every pose):\n\n"
     << CalibrationTable(*curve);
  md.precision(4);
  md << "\nBrier score (the mean squared difference of the probability and being within 1 m; "
        "lower is better): "
     << (predicted.empty() ? 0.0 : brier / static_cast<double>(predicted.size())) << "\n";
  md.precision(2);
}

// results.md: how many runs of each set, the error tables, the targets and the
// reliability tables; the calibration curve in *curve.
std::string ResultsMarkdown(const std::vector<EvalReport>& reports, const SuiteOptions& o,
                            std::vector<CalibrationBin>* curve) {
  std::ostringstream md;
  md.setf(std::ios::fixed);
  md.precision(2);
  size_t development = 0;
  for (const EvalReport& r : reports) development += r.split == "development";
  md << "Runs: " << development << " development (seeds 11 and up), "
     << reports.size() - development << " validation (seeds 1-10).\n\n";
  Grouped grouped;
  for (const EvalReport& r : reports) {
    grouped.cell[{r.plan_id, r.scenario}][r.method].push_back(r.mean_error_m);
    grouped.by_method[r.method].push_back(&r);
  }
  WriteErrorTables(grouped, o, md);
  WriteTargetsTable(reports, grouped, o, md);
  WriteReliabilityTables(reports, o, md, curve);
  return md.str();
}

// SVGs of the best and the worst run of the first method, on the plan as drawn.
void WriteBestAndWorst(const std::vector<EvalReport>& reports, const std::vector<SuiteRun>& runs,
                       const std::map<std::string, FloorPlan>& loaded, const SuiteOptions& o) {
  std::vector<const EvalReport*> registered;
  for (const EvalReport& r : reports)
    if (r.method == o.methods.front()) registered.push_back(&r);
  if (!registered.empty()) {
    auto [best, worst] = std::minmax_element(
        registered.begin(), registered.end(),
        [](const EvalReport* a, const EvalReport* b) { return a->mean_error_m < b->mean_error_m; });
    for (const auto& [name, r] : {std::pair{"best", *best}, std::pair{"worst", *worst}}) {
      for (const SuiteRun& run : runs) {
        if (run.plan_id != r->plan_id || run.scenario != r->scenario || run.seed != r->seed)
          continue;
        const FloorPlan drawn = run.drawn_plan.empty()
                                    ? loaded.at(run.plan_path)
                                    : platform::LoadFloorPlan(run.drawn_plan).plan;
        std::ofstream(fs::path(o.out) / "svg" / (std::string(name) + ".svg")) << ToSvg(drawn, *r);
      }
    }
  }
}

// Every plan, by its path; false, with the error logged, when one does not load.
bool LoadPlans(const std::vector<std::string>& plans, std::map<std::string, FloorPlan>* loaded) {
  for (const std::string& p : plans) {
    FloorPlanParse parse = platform::LoadFloorPlan(p);
    if (!parse.ok()) {
      spdlog::error("{}", parse.error);
      return false;
    }
    (*loaded)[p] = parse.plan;
  }
  return true;
}

// results.json (a line per run, in the order of plan, scenario, seed and method),
// results.md with the calibration curve's SVG, the best and worst runs' SVGs; the tables
// on stdout.
void WriteResults(std::vector<EvalReport> reports, const std::vector<SuiteRun>& runs,
                  const std::map<std::string, FloorPlan>& loaded, const SuiteOptions& o) {
  std::sort(reports.begin(), reports.end(), [](const EvalReport& a, const EvalReport& b) {
    return std::tie(a.plan_id, a.scenario, a.seed, a.method) <
           std::tie(b.plan_id, b.scenario, b.seed, b.method);
  });
  {
    std::ofstream json(fs::path(o.out) / "results.json");
    for (const EvalReport& r : reports) json << ToJson(r) << "\n";
  }
  std::vector<CalibrationBin> curve;
  const std::string md = ResultsMarkdown(reports, o, &curve);
  std::ofstream(fs::path(o.out) / "svg" / "calibration.svg") << CalibrationSvg(
      {{o.methods.front() + ": published probability, every pose of the suite", curve}});
  std::ofstream(fs::path(o.out) / "results.md") << md;
  WriteBestAndWorst(reports, runs, loaded, o);
  std::fputs(md.c_str(), stdout);
}

int RunSuite(const SuiteOptions& o) {
  spdlog::set_level(spdlog::level::warn);  // thousands of registrations: only problems
  v1::FloorposedConfig base_config;
  std::string config_error;
  if (!platform::LoadConfig(o.config, &base_config, &config_error)) {
    spdlog::error("{}", config_error);
    return 2;
  }
  const std::vector<std::string> plans = PlanFiles(o.plans);
  if (plans.empty()) {
    spdlog::error("no floor plans (*.geojson) found in the given --plans");
    return 2;
  }
  for (const char* dir : {"recordings", "svg", "plans"})
    fs::create_directories(fs::path(o.out) / dir);
  std::vector<SuiteRun> runs = PlanRuns(o, plans);
  std::map<std::string, FloorPlan> loaded;
  if (!LoadPlans(plans, &loaded)) return 1;

  // Work items: one simulation, then its evaluations; spread over the cores.
  std::vector<EvalReport> reports;
  std::mutex mu;
  std::atomic<int> failures{0};
  ParallelFor(runs.size(), o.jobs, "eval-suite", [&](size_t i, Progress& progress) {
    SuiteRun& run = runs[i];
    std::string plan_path;
    if (!SimulateRun(o, loaded.at(run.plan_path), &run, &plan_path)) {
      ++failures;
      return;
    }
    for (const std::string& method : o.methods) {
      EvalReport report;
      if (!EvaluateRun(base_config, o, run, plan_path, method, &report)) {
        ++failures;
        continue;
      }
      std::lock_guard lock(mu);
      progress.Clear();
      std::printf(
          "%-12s %-10s seed %lu %-16s mean %6.2f m  max %6.2f m  reliable %3.0f%% (%3.0f%% "
          "within 1 m)\n",
          run.plan_id.c_str(), run.scenario.c_str(), static_cast<unsigned long>(run.seed),
          report.method.c_str(), report.mean_error_m, report.max_error_m,
          100 * report.reliable_fraction, 100 * report.reliable_precision_1m);
      std::fflush(stdout);
      report.track.shrink_to_fit();
      report.plan_poses.clear();
      reports.push_back(std::move(report));
    }
  });

  WriteResults(std::move(reports), runs, loaded, o);
  return failures ? 1 : 0;
}

}  // namespace

Run AddEvalSuiteCommand(CLI::App& app) {
  auto o = std::make_shared<SuiteOptions>();
  auto* plans = app.add_option("--plans", o->plans, "floor plan files or directories (*.geojson)");
  auto* carmen = app.add_option("--carmen", o->carmen.dir,
                                "evaluate every <name>-corrected.log.gz of this directory that has "
                                "<name>_gt.tum and <name>_plan.yaml (with <name>_odom.tum when "
                                "there is one) as import-carmen and eval would, one row per log")
                     ->excludes(plans);
  app.add_option("--waypoints", o->waypoints.dir,
                 "walk every walk of every floor under this directory (a folder with a plan and "
                 "waypoints.csv) as simulate --waypoints would, evaluated with the wall pick and "
                 "without")
      ->excludes(plans)
      ->excludes(carmen);
  app.add_option("--walks", o->waypoints.walks,
                 "with --waypoints: the first this many walks of each floor (0: all; a walk "
                 "without a pick searches the whole plan, seconds a search on a mall)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--seeds", o->seeds, "seeds per plan and scenario")->capture_default_str();
  app.add_option("--out", o->out, "output directory")->required();
  app.add_option("--scenarios", o->scenarios, "scenarios (simulate --help describes them)")
      ->delimiter(',')
      ->check(CLI::IsMember(sim::ScenarioNames()))
      ->capture_default_str();
  app.add_option("--methods", o->methods, "methods and baselines")
      ->delimiter(',')
      ->check(CLI::IsMember({"mcl", "none", "best-fit"}))
      ->capture_default_str();
  app.add_option("--length", o->length_m, "walk length per run, metres (0: default)");
  app.add_option("--jobs", o->jobs, "parallel runs (0: one per core)");
  app.add_option("--config", o->config, "floorposed configuration to evaluate with");
  app.add_option("--first-seed", o->first_seed, "seeds run from this one (calibrate on others)")
      ->capture_default_str();
  app.add_flag("--no-pick", o->no_pick,
               "drop the walks' wall picks and place the wearer by searching the plan "
               "(tracking.global_search); adds the placement table");
  app.add_flag("--kidnap", o->kidnap,
               "start every walk with a wrong wall pick (10 m and 90 degrees off, as "
               "`simulate --kidnap`) and search the plan (tracking.global_search); adds the "
               "kidnap table");
  return [o] {
    for (RealSuiteOptions* real : {&o->carmen, &o->waypoints}) {
      real->out = o->out;
      real->config = o->config;
      real->jobs = o->jobs;
    }
    if (!o->carmen.dir.empty()) return RunCarmenSuite(o->carmen);
    if (!o->waypoints.dir.empty()) return RunWaypointSuite(o->waypoints);
    if (o->plans.empty()) {
      spdlog::error("eval-suite: give --plans, --carmen or --waypoints");
      return 2;
    }
    return RunSuite(*o);
  };
}

}  // namespace floorpose::tools
