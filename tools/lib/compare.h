// Two eval-suite runs of the same walks side by side (`floorpose eval-compare`): the suite's
// headline figures for each and their difference, with a 95% interval from a paired
// bootstrap over the runs (Efron and Tibshirani, An Introduction to the Bootstrap, ch. 13).
// A few walks carry most of a table's false poses, so a difference of a few hundred poses
// can be one walk; the interval says whether a change is more than that.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace floorpose::tools {

// What one run contributes (a line of results.json).
struct RunFigures {
  std::string key;  // method, plan, scenario, seed: the same walk in both suites
  double mean_error_m = 0;
  double max_error_m = 0;
  double scored_poses = 0;  // poses after the first alignment
  double reliable_poses = 0;
  double false_poses = 0;  // RELIABLE more than 1 m off
  double brier = 0;        // the run's Brier score (EvalReport::brier)
  // Seconds from the first alignment to the first pose RELIABLE and within 1 m (a wrong
  // pick's recovery, a search's placement); negative: never.
  double time_to_recovered_s = -1;
};

// The suite's figures over a set of runs.
struct SuiteFigures {
  double mean_error_m = 0;  // mean over runs of each run's mean error
  double runs_over_5m = 0;  // runs with a pose more than 5 m off
  double reliable = 0;      // share of scored poses flagged RELIABLE
  double precision = 1;     // share of RELIABLE poses within 1 m
  double false_poses = 0;
  double brier = 0;  // over every scored pose of the runs
  // Share of runs RELIABLE within 1 m within kBackAfterKidnapS (evaluation.h) of the first
  // alignment (issue 43's kidnap target), and runs never so.
  double recovered = 0;
  double never_recovered = 0;
};
SuiteFigures Figures(const std::vector<const RunFigures*>& runs);

struct Difference {
  const char* name;
  const char* unit = "";      // "%": a share, printed times 100
  int digits = 0;             // decimals to print it with
  double base = 0, next = 0;  // the figure of each suite (a share as a fraction)
  double low = 0, high = 0;   // 95% interval of next - base
};

// The runs of `base` and `next` paired by key (those of one only are left out), and
// each figure's difference with its interval from `resamples` draws (seeded).
std::vector<Difference> Compare(const std::vector<RunFigures>& base,
                                const std::vector<RunFigures>& next, int resamples, uint64_t seed);

// The runs of an eval-suite results.json; "" and the runs, or the error.
std::string ReadRuns(const std::string& path, std::vector<RunFigures>* runs);

}  // namespace floorpose::tools
