// `floorpose eval` as functions: a recording through the daemon's Engine on a virtual
// clock (registrations inline, so the run is deterministic), plan poses scored against
// the recording's ground truth with the thesis' metrics (chapter 7).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/floor_plan.h"
#include "core/tracking/alignment.h"
#include "floorpose/v1/config.pb.h"
#include "floorpose/v1/floorpose.pb.h"
#include "platform/recording.h"

namespace floorpose::tools {

enum class Baseline {
  kNone,         // registrations as configured (no baseline)
  kNoAlgorithm,  // the wall pick only, never registered (thesis "no algorithm" rows)
  kBestFit,      // one SE(2) fitted after the fact to the whole walk (thesis table 7.2)
};

struct EvalPose {
  int64_t stamp_ns = 0;
  double x = 0, y = 0, heading = 0;  // estimate on the plan
  double true_x = 0, true_y = 0;
  double error_m = 0;
  bool reliable = false;
  bool unreliable = false;  // flagged UNRELIABLE (not DEGRADED)
  double probability = 0;   // published probability of being within 1 m
  std::string reason;       // published reliability reason
  uint32_t marker = 0;
  uint64_t alignment_version = 0;
  bool registered = false;  // the alignment in use came from a registration
};

// Issue 41's split of the evaluation data. Settings may be tuned on development runs; a
// setting is kept only if it does not lose on validation runs, on which nothing is tuned.
// Simulated seeds 11 and up, CARMEN aces, csail, freiburg-101 and orebro, and ILC floors
// B1, F1 and F2 are development; everything else (seeds 1-10, the other logs and floors,
// and any data of a user's) is validation.
const char* SimulatedSplit(uint64_t seed);
const char* CarmenSplit(const std::string& log);
const char* IlcSplit(const std::string& floor);

// The seconds within which a loss of tracking should be RELIABLE within 1 m again (issue
// 43's target for `relocalize`).
constexpr double kBackAfterLossS = 20.0;
// ...and after a wrong pick, from the pick (issue 43's target for `--kidnap`).
constexpr double kBackAfterKidnapS = 30.0;
// How far the wearer has moved at the first step, metres: over the truth's jitter while
// standing (none in the simulator), under one stride.
constexpr double kFirstStepM = 0.3;

// The scored poses after one loss of tracking: a pose after more than
// tracking.motion.lost_after_s of none, or after one saying TRACKING_LOST, as the tracker
// takes it. Up to the next loss or the end of the walk.
struct LossScore {
  double resumed_s = 0;       // the first pose after the loss, from the first scored pose
  double back_s = -1;         // from it to the first RELIABLE pose within 1 m (-1: none)
  double followed_s = 0;      // scored walk after it (to the last pose before the next loss)
  size_t false_reliable = 0;  // RELIABLE poses more than 1 m off before back
  // Followed long enough to tell: back within kBackAfterLossS, or walked that long.
  bool back_in_time() const { return back_s >= 0 && back_s <= kBackAfterLossS; }
  bool timed() const { return back_in_time() || followed_s >= kBackAfterLossS; }
};

// Scores the track after each loss: `resumed` holds the stamp of the first pose after each,
// in order.
std::vector<LossScore> ScoreLosses(const std::vector<EvalPose>& track,
                                   const std::vector<int64_t>& resumed);

struct EvalReport {
  std::string method;
  std::string scenario, plan_id;
  uint64_t seed = 0;
  std::string split;           // "development" or "validation"
  double cpu_s = 0;            // CPU seconds the evaluation took (eval-suite)
  size_t poses = 0;            // scored: aligned plan poses with ground truth
  size_t unaligned_poses = 0;  // before the first alignment: not scored
  double mean_error_m = 0, p95_error_m = 0, max_error_m = 0, final_error_m = 0;
  double marker_mean_error_m = 0;
  size_t divergences = 0;  // poses more than 5 m off
  // The pick's own error (the first scored pose), and from the first pose whose alignment
  // came from a registration on: its delay after the first scored pose (-1: never), and
  // the mean and max error of the poses since (0 when none).
  double pick_error_m = 0, first_fix_s = -1;
  double settled_mean_error_m = 0, settled_max_error_m = 0;
  uint64_t registrations = 0, accepted = 0;
  double reg_time_ms_median = 0, reg_time_ms_max = 0;
  double reliable_fraction = 0;      // of poses flagged RELIABLE
  double reliable_precision_1m = 0;  // of those, the share within 1 m
  // The published probability's Brier score: the mean over scored poses of (probability
  // - 1 if within 1 m, else 0)^2. A proper scoring rule (Brier 1950): lowest for a
  // probability that is both calibrated and sharp, so noise settings are tuned by it.
  double brier = 0;
  // From the first plan pose to the first scored pose flagged RELIABLE (-1: never), and
  // the poses flagged RELIABLE while more than 1 m off.
  double time_to_first_reliable_s = -1;
  double first_reliable_error_m = -1;  // ...and how far off that pose was
  size_t false_reliable_poses = 0;
  // From the first scored pose (a wrong pick: simulate --kidnap) to the first flagged
  // UNRELIABLE, and to the first RELIABLE within 1 m (-1: never).
  double time_to_unreliable_s = -1, time_to_recovered_s = -1;
  // From the first pose published (placed or not, as time_to_first_reliable_s) to the
  // wearer's first step: the first true position kFirstStepM or more from the first (-1:
  // never). Issue 43 times a placement in seconds of walking; a wearer may stand first.
  double first_step_s = -1;
  // The poses flagged RELIABLE while more than 1 m off before that first RELIABLE pose
  // within 1 m (all of them when there is none): a wrong place trusted, not drift.
  size_t false_reliable_before_recovered = 0;
  // Every loss of tracking (the SLAM frame may have jumped), in order; issue 43 asks each
  // to be RELIABLE within 1 m again within kBackAfterLossS with no RELIABLE pose more
  // than 1 m off before.
  std::vector<LossScore> losses;
  size_t global_searches = 0;  // whole-plan searches run (placements and checks)
  // The first of them: seconds into the recording (-1: none), and the order among its
  // places of the first within 1 m of the truth at the wearer (-1: none was). A late
  // placement either waited for the walls a search needs or chose among its places.
  double first_search_s = -1;
  int first_search_truth = -1;
  // A .floors plan set: floors the daemon changed to, and poses published with another
  // floor than the truth's.
  size_t floor_changes = 0, wrong_floor_poses = 0;
  std::vector<EvalPose> track;
  std::vector<v1::PlanPose> plan_poses;     // as the Engine published them, in order
  size_t plan_tracks = 0;                   // PlanTrack messages published
  std::optional<v1::ExploredMap> explored;  // the last explored map published
  v1::PlanTrack last_plan_track;            // the last of them
};

// Runs `recording` against the plan in config.plan_path() (config as the daemon's; the
// device id is taken from the recording). False with a message on unreadable input.
// With `session`, the inputs and everything the Engine publishes are written there as
// `floorpose record` would have recorded the live session (receive stamps: the inputs').
// With `no_pick`, the recording's wall picks are dropped (with config tracking.global_search,
// the wearer is placed by searching the plan).
bool Evaluate(const v1::FloorposedConfig& config, const std::string& recording, Baseline baseline,
              EvalReport* report, std::string* error, platform::RecordingWriter* session = nullptr,
              bool no_pick = false);

// The q-quantile (0..1) of v, nearest rank; 0 for an empty v.
double Percentile(std::vector<double> v, double q);
// The mean of a non-empty v.
double Mean(const std::vector<double>& v);

// A run's losses of tracking counted: followed long enough to tell (LossScore::timed),
// back within kBackAfterLossS, and the poses RELIABLE more than 1 m off before back.
struct LossCounts {
  size_t timed = 0, back = 0, false_reliable = 0;
};
LossCounts CountLosses(const std::vector<LossScore>& losses);

// The report as one JSON object (the keys of the issue) and as readable text.
std::string ToJson(const EvalReport& report);
std::string ToText(const EvalReport& report);

// One line per scored pose: stamp, estimate, truth, error, flag, probability, reason.
std::string ToTrackCsv(const EvalReport& report);

// An SVG of the plan, the true and the estimated trajectories and the markers.
std::string ToSvg(const FloorPlan& plan, const EvalReport& report);

}  // namespace floorpose::tools
