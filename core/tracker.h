// The tracker: the alignment T_plan_slam in use, how it starts (wall pick, flip), when
// to register, whether to accept a result, and how reliable a corrected pose is. The
// daemon and the offline tools drive the same object; time is always an argument.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/alignment_filter.h"
#include "core/closest_wall_index.h"
#include "core/global_search.h"
#include "core/registration.h"
#include "core/se2.h"

namespace floorpose {

// The reliability model: a logistic regression over ReliabilityFeatures, fitted by
// `floorpose calibrate` on simulated walks (docs/evaluation.md). The defaults are the
// fit reported there.
struct ReliabilityModel {
  static constexpr int kFeatures = 8;
  double bias = -0.1983;
  // In the order of ReliabilityFeatures::Vector().
  std::array<double, kFeatures> weights = {4.827,   -11.76,  -0.6569, 0.0,
                                           -0.1433, -0.2413, 0.3262,  -0.01431};
  // The way each feature may move the probability (+1 up, -1 down): a fit that, say,
  // rewards heading uncertainty because it happens to correlate with something else in
  // the training walks would stay confident on a long walk without walls.
  static constexpr std::array<int, kFeatures> kSigns = {+1, -1, -1, -1, -1, -1, +1, -1};
  double reliable_probability = 0.9;  // RELIABLE at or above this
  double degraded_probability = 0.5;  // DEGRADED at or above this, else UNRELIABLE

  // The probability of being within 1 m for features in that order.
  double Probability(const std::array<double, kFeatures>& features) const;
};

struct TrackerOptions {
  IcpOptions icp;
  RegistrationMethod method = RegistrationMethod::kIcp;
  HoughOptions hough;
  AlignmentFilterOptions filter;
  ReliabilityModel reliability;
  double wall_buffer_m = 0.0;      // see RegistrationOptions
  double clip_margin_m = 0.0;      // see RegistrationOptions
  double pick_search_m = 2.5;      // correlative search after a pick or flip, metres
  double pick_search_rad = 0.175;  // ...and radians
  double pick_tie_ratio = 0.9;     // see RegistrationOptions::search_tie_ratio
  double search_sigmas = 3.0;      // later runs search this many filter sigmas at the wearer...
  double search_min_m = 1.5;       // ...when that reaches this far (at most the pick search)
  double search_tie_ratio = 0.5;   // ...and tell places apart by nearness up to this ratio
  double turn_sigma_rad = 1.0 * M_PI / 180;  // the walls' directions as a heading measurement
  double pick_sigma_m = 1.5;                 // uncertainty of a wall pick at its point, metres
  double pick_sigma_rad = 5.0 * M_PI / 180;  // ...and of its heading
  double confirm_m = 0.5;                    // a gated result is taken when later ones land within
  double confirm_rad = 0.035;                // ...this of it...
  double confirm_walk_m = 10.0;              // ...over this many metres walked...
  double jump_score_ratio = 0.7;  // ...and it fits the cloud this much better than the one in use
  // A gated result is taken at once, without confirmation, when it explains the walls and
  // the alignment in use does not: at least jump_clear_inliers of the cloud within the
  // inlier threshold of a plan wall under the result, fewer under the alignment in use,
  // and a score at most jump_clear_ratio times the in-use one (0: never at once). A
  // wheel slipping in a turn or a SLAM's heading jump puts the alignment in use degrees
  // off in seconds; each correct result after it disagrees with the last as the
  // odometry goes on slipping, so none would be confirmed. Off for headsets (their
  // simulated walks slide along corridors whose walls the plan lacks), on for wheels.
  double jump_clear_ratio = 0.0;
  double jump_clear_inliers = 0.65;
  // After a result beyond the gate, while the alignment in use explains fewer than
  // jump_clear_inliers of the walls, the next registration searches pick_search_m and
  // _rad around it: the filter is sure of a place the walls say is wrong.
  bool search_unexplained = true;
  double max_ambiguity = 0.7;       // results after a pick with RegistrationResult::ambiguity above
                                    // this: refused until later ones confirm the place (as jumps)
  double first_inlier_ratio = 0.9;  // results after a pick with fewer inliers: refused
  // ...and after a place found by searching the plan (refined on a minute of walls).
  double searched_first_inlier_ratio = 0.75;
  double clear_ambiguity = 0.3;    // a first result this unambiguous, with its inliers, and
                                   // within the pick search of the pick at the wearer: taken
                                   // at once (others wait for the next result to agree)
  double score_cap_m = 0.2;        // distances capped here in the "better fit" score
  double worse_fit_ratio = 1.25;   // results scoring worse than this times the one in use: rejected
  bool local_meshes = false;       // register only meshes new since the last run (thesis "local")
  uint32_t min_new_points = 500;   // register after this many new wall points...
  double min_walk_m = 2.0;         // ...or this many metres walked with new points...
  double max_interval_s = 3.0;     // ...or after this long with any new points
  uint32_t min_points = 50;        // no registration on fewer points...
  uint32_t check_min_points = 15;  // ...but this many to check a pick, flip or search's place
  // A step of the path under the alignment in use (since it was last set) through a plan
  // wall, path_check_margin_m or more from the wall's ends: UNRELIABLE, until an alignment
  // under which the walk of the registration's window goes through no wall (Offer).
  bool path_check = true;
  double path_check_margin_m = 0.4;
  // The wearer more than this far outside the plan's bounding box under the alignment in
  // use: UNRELIABLE (the plan has no walls there to check against; a wrong pick or place
  // often puts the wearer outside the building). 0: no such check.
  double off_plan_margin_m = 1.0;
  size_t history = 16;  // accepted alignments kept
  // Without a pick: search the whole plan (GlobalSearch) once this many wall points are
  // in, every global_interval_s, over the walls of the last global_window_s (0: all).
  // The places found are refined and ranked (RefinePlaces); only a place of rank 0 (it
  // fits global_place_min_inliers of the walls, and the path under it crosses fewer than
  // global_max_crossings walls, or it fits global_excuse_crossings times better than any
  // other, and no more than under any other) can lead. A search counts towards its lead
  // when the next one's error is at least global_min_lead times its own (a search where
  // it stays first by less neither counts nor breaks the row); it has led once
  // it was ahead global_confirm_searches or more searches in a row and their leads
  // multiply to what as many of 1 / global_lead_ratio would. It is clear of the next at
  // 1 / global_clear_ratio. The best is taken when it was clear in 2 searches in a row
  // or has led; it is RELIABLE only once it has led. Once aligned (a pick too) the search
  // goes on as a check while in doubt (the place not yet confirmed, or the walls fitting
  // the alignment in use under global_min_inliers): another place that has led over the
  // checks and is clear of the one in use replaces it (recovery); when the walls do not
  // fit the one in use, a place that fits better by a lead does.
  bool global_search = false;
  uint32_t global_min_points = 150;
  // ...and to check an alignment in use (it has that place to beat), every this often.
  uint32_t global_check_min_points = 60;
  double global_check_interval_s = 2.0;
  double global_interval_s = 3.0;
  double global_window_s = 60.0;
  double global_clear_ratio = 0.5;
  double global_lead_ratio = 0.8;
  double global_min_lead = 1.05;
  uint32_t global_confirm_searches = 3;
  double global_min_inliers = 0.6;
  // A searched place fits (rank 0, may lead) from this share of the walls, lower than
  // global_min_inliers: where the plan lacks walls that stand (a `mismatch` walk) the true
  // place fits 44-58% of a minute's walls for minutes on end, and the other places less.
  double global_place_min_inliers = 0.45;
  // A place under which the wearer's path over the window crosses this many plan walls
  // (path_check_margin_m clear of their ends) does not fit either; 0: any number.
  uint32_t global_max_crossings = 2;
  // ...unless every other place's error is at least this many times its own (0: never):
  // the SLAM's drift over the window makes the path under the true place clip walls too.
  double global_excuse_crossings = 3.0;
  // A wall point hidden from the path under a place (HiddenPoints within this reach)
  // counts as a miss in its fit (RefineOptions::sight_reach_m); 0: no sight check.
  double global_sight_reach_m = 4.5;
  // The plan's walls in clear sight within this reach of the path under a place, that
  // no wall point lies near (CountUnseenWalls), beyond global_unseen_allowance of them,
  // count against its fit, and beyond RefineOptions::unseen_max_ratio it does not fit
  // (RefineOptions::unseen_reach_m); 0: no such check.
  double global_unseen_reach_m = 2.0;
  double global_unseen_allowance = 0.5;
  // A place of rank 0 that the best is not clear of (global_twin_clear_ratio), under which the
  // plan looks the same from the walk as under the best (PlanAlike over the walls within
  // global_sight_reach_m: at least this share of them lie on walls under both), is one
  // the walls cannot tell from it: a hall's half-turn twin, a copy of a room. The best
  // does not lead while there is one (its row starts over). The engine's search also
  // looks for the best's half-turn twin. 0: neither.
  double global_alike_share = 0.9;
  // ...a twin the best is not clear of at this ratio (its error under this times the
  // twin's): twins 97-99% alike were seen to fit 2.4 times apart by the drift alone.
  double global_twin_clear_ratio = 0.25;
  // A search whose grid returned as many places as it may, the last scoring at least this
  // share of the first's grid score, is crowded: more places as good may be left out (a
  // hall of repeated bays), the true one or a twin among them, so its lead does not count
  // (the row holds). The engine's grid returns up to 12 places while they score this
  // share of the best (GlobalSearchOptions::crowd_ratio). 0: no such rule.
  double global_crowded_ratio = 0.98;
};

// Thesis section 6.3.4: one wall point with its normal, seen by the headset (slam
// frame, horizontal part) and chosen on the plan.
struct WallPick {
  Eigen::Vector2d slam_point, slam_normal;
  Eigen::Vector2d plan_point, plan_normal;
};

// Equation 6.2 in 2D: rotate the measured normal onto the plan normal, then translate
// the measured point onto the plan point. Nothing when a normal is (near) zero.
std::optional<Se2> AlignFromWallPick(const WallPick& pick);

enum class ReliabilityFlag { kReliable, kDegraded, kUnreliable };
enum class TrackState { kWaitingForPlan, kWaitingForAlignment, kTracking, kDegraded, kLost };
enum class AlignmentSource { kNone, kWallPick, kFlip, kRegistration, kGlobalSearch };

// The registration options for a run starting from an alignment of the given source:
// after a pick or flip, with the correlative search, its rotations about `pivot` (plan).
RegistrationOptions ToRegistrationOptions(const TrackerOptions& options, AlignmentSource from,
                                          const std::optional<Eigen::Vector2d>& pivot);

// What the tracker knows about the alignment in use at a pose: the inputs of the
// reliability model.
struct ReliabilityFeatures {
  double inlier_ratio = 0;       // of the latest registration cloud, under the alignment in use
  double inlier_rmse_m = 0;      // ...of those inliers
  double position_sigma_m = 0;   // filter: one sigma at the wearer (largest axis)
  double heading_sigma_deg = 0;  // filter: one sigma of the heading
  double weakest_direction = 0;  // smallest eigenvalue of the mean information, as metres of
                                 // uncertainty per point: large in a corridor
  double disagreement = 0;       // Mahalanobis distance of the latest registration (sqrt)
  double accepted = 0;           // registrations fused since the pick, log(1 + n)
  double walked_m = 0;           // since the latest fused registration, metres (log(1 + m))
  std::array<double, ReliabilityModel::kFeatures> Vector() const {
    return {inlier_ratio,      inlier_rmse_m, position_sigma_m, heading_sigma_deg,
            weakest_direction, disagreement,  accepted,         walked_m};
  }
  static const char* Name(int i);
};

struct Reliability {
  ReliabilityFlag flag = ReliabilityFlag::kUnreliable;
  double probability = 0.0;  // of the plan position being within 1 m
  double rmse_m = 0.0;
  std::string reason;
};

struct PlanPoseEstimate {
  Pose2 pose;  // plan frame
  uint64_t alignment_version = 0;
  Reliability reliability;
};

struct AlignmentState {
  Se2 T_plan_slam;
  uint64_t version = 0;  // 0: none yet
  AlignmentSource source = AlignmentSource::kNone;
  int64_t stamp_ns = 0;
  std::optional<RegistrationResult> registration;  // when source is kRegistration
};

// What a restart needs to resume the alignment where it was (platform/engine.h keeps it
// in the state snapshot): the alignment without its registration, and the filter.
struct TrackerState {
  AlignmentState alignment;
  uint64_t next_version = 1;
  Eigen::Matrix3d P = Eigen::Matrix3d::Identity();  // filter covariance about pivot
  Eigen::Vector2d pivot = Eigen::Vector2d::Zero();
  double drift_scale = 1.0;
  std::optional<Eigen::Vector2d> pick_plan_point;
  Eigen::Vector2d start_pivot = Eigen::Vector2d::Zero();
  uint32_t fused = 0;
};

class Tracker {
 public:
  struct Decision {
    bool accepted = false;
    std::string reason;
  };
  explicit Tracker(TrackerOptions options) : options_(std::move(options)) {}

  // A new plan drops the alignment: it belonged to the old plan.
  void SetPlan(std::shared_ptr<const ClosestWallIndex> index);
  void Reset();  // drops the alignment, keeps the plan
  // Another floor's plan in the same x-y frame (a .floors set): the alignment and what
  // the filter knows stay (under a new version: a registration running against the
  // floor left is stale); a result waiting for confirmation and the last fit go.
  void ChangeFloor(std::shared_ptr<const ClosestWallIndex> index);

  bool has_plan() const { return index_ != nullptr; }
  bool has_alignment() const { return alignment_.version > 0; }
  const AlignmentState& alignment() const { return alignment_; }
  const std::shared_ptr<const ClosestWallIndex>& index() const { return index_; }
  const TrackerOptions& options() const { return options_; }
  // The registration options for the next run: after a pick or flip, the correlative
  // search with its rotations about the pick's point; later, a search as wide as the
  // alignment is uncertain at the wearer (search_sigmas), when that is wide enough, or
  // as after a pick when the walls stopped fitting it (search_unexplained).
  RegistrationOptions NextRegistrationOptions() const;

  TrackerState SaveState() const;
  // Resumes a saved state on the plan in use; until the next registration checks it
  // against the walls the flag says so (DEGRADED). Returns why not (no plan, values that
  // are not finite or not a covariance), or empty.
  std::string RestoreState(const TrackerState& state);

  // Returns an error message, or empty on success.
  std::string ApplyWallPick(const WallPick& pick, int64_t stamp_ns);
  // Turns the alignment by 180 degrees about the last pick's plan point, or about the
  // wearer's last plan position when there was no pick (the pick's normal may face the
  // other way in the headset than on the plan).
  std::string Flip(int64_t stamp_ns);

  // A pose on the plan under the alignment in use, with its reliability; Correct also
  // takes it as the wearer's newest (the walk and turn the filter's drift grows with),
  // Project does not (a late pose).
  PlanPoseEstimate Correct(const Pose2& pose_slam);
  PlanPoseEstimate Project(const Pose2& pose_slam) const;

  // Scheduling: due when aligned, with enough points, and enough new data, distance
  // walked or time.
  bool RegistrationDue(int64_t now_ns, size_t live_points, size_t new_points) const;
  // The wall points a registration needs now: check_min_points while the alignment is a
  // pick, flip or search's place not yet registered, else min_points.
  uint32_t MinPoints() const;
  void MarkRegistrationStarted(int64_t now_ns) {
    last_start_ns_ = now_ns;
    walked_since_start_m_ = 0;
  }
  // Global placement and its checks (see TrackerOptions::global_search): due with
  // global_min_points, every global_interval_s without an alignment and while it is in
  // doubt (never otherwise: a confirmed place whose walls fit is not replaced). OfferPlaces takes a
  // search's refined places (best fit first; `centre_slam` is the cloud's centre) made while
  // alignment `based_on_version` was in use (0: none): it places the wearer, confirms the place in
  // use, or replaces it, as a pick would be taken (the cloud's centre on the plan is the
  // pivot of the correlative search after it).
  bool GlobalSearchDue(int64_t now_ns, size_t live_points) const;
  // The wall points of the window a search needs: global_min_points to place,
  // global_check_min_points to check an alignment in use.
  uint32_t GlobalMinPoints() const;
  void MarkGlobalSearchStarted(int64_t now_ns) { last_global_ns_ = now_ns; }
  // The best place of the latest search, if any: the next search refines it with the
  // grid's places, since the grid's coarse scores may leave it out.
  const std::optional<Se2>& leading_place() const { return leading_place_; }
  // The wearer's path went through a wall of the plan under the alignment in use.
  bool path_crossed() const { return crossings_ > 0; }
  // The alignment in use is a wall pick or its flip: no registration has placed the
  // wearer since.
  bool on_pick() const {
    return alignment_.source == AlignmentSource::kWallPick ||
           alignment_.source == AlignmentSource::kFlip;
  }
  // `full_grid_scores`: when the grid returned as many places as it may, their grid
  // scores, best first (for global_crowded_ratio); else empty.
  Decision OfferPlaces(const std::vector<GlobalPlace>& places, const Eigen::Vector2d& centre_slam,
                       uint64_t based_on_version, int64_t stamp_ns,
                       const std::vector<double>& full_grid_scores = {});
  // Whether the walls of the latest registration fit the alignment in use under
  // global_min_inliers (the latest fit says so; nothing before the first).
  bool WallsDoNotFit() const;
  // How far the wearer's latest position lies outside the plan's bounding box under the
  // alignment in use, beyond off_plan_margin_m (0: within it, or no check).
  double OffPlanM() const;

  // Offers a finished registration that started from alignment `based_on_version` on
  // `cloud`. Fused into the alignment when it still applies, fits the cloud about as
  // well as the alignment in use or better (section 6.4.3), and agrees with it within
  // the filter's gate; a result beyond the gate is taken only when the next one
  // confirms it (the navigation app's rule for jumps). `path_slam` is the wearer's walk
  // over the cloud's window (slam frame, in order): a first place after a pick or flip
  // that walks it through a wall of the plan (path_check) is not taken, and after a step
  // through a wall the flag stays while the walk goes through one under the result too.
  Decision Offer(const RegistrationResult& result, const std::vector<Eigen::Vector2d>& cloud,
                 uint64_t based_on_version, int64_t stamp_ns,
                 const std::vector<Eigen::Vector2d>& path_slam = {});

  // Until a first place after a pick or flip is taken, the pick's heading error swings
  // its error at the wearer into metres as they walk away from the pick. The walls' own
  // directions (HoughRotation, within the pick search) fix the heading without a place:
  // turns the alignment by omega_rad about the pick's point, keeping its position there
  // (a measurement of turn_sigma_rad, fused with the filter's heading). Returns the turn
  // made: none when a first place was taken, the alignment changed since
  // `based_on_version`, or omega is beyond 3 sigma of the two.
  std::optional<double> TurnToWalls(double omega_rad, uint64_t based_on_version, int64_t stamp_ns);

  TrackState state() const;
  Reliability CurrentReliability() const;
  ReliabilityFeatures CurrentFeatures() const;
  // The model's probability and flag for given features (public for calibration).
  Reliability Assess(const ReliabilityFeatures& f) const;

  // How much faster than the configured prior the SLAM drifts, as the filter learnt it
  // from the registrations (AlignmentFilterOptions::drift_window).
  double drift_scale() const { return filter_.drift_scale(); }
  // Another drift model from now on (the device said it moves on another odometry): the
  // filter's options, confirm_walk_m and jump_clear_ratio of `options`; the alignment, its
  // covariance and what the filter learnt stay.
  void SetOdometryOptions(const TrackerOptions& options) {
    options_.filter = options.filter;
    options_.confirm_walk_m = options.confirm_walk_m;
    options_.jump_clear_ratio = options.jump_clear_ratio;
    filter_.set_options(options.filter);
  }

  // The latest accepted alignments, oldest first.
  const std::vector<AlignmentState>& history() const { return history_; }

 private:
  void SetAlignment(const Se2& T, AlignmentSource source, int64_t stamp_ns);
  // Why a result after a pick or flip is not to be trusted yet (ambiguous, or too few
  // of its points fit), or empty.
  std::string FirstRegistrationDoubt(const RegistrationResult& result) const;
  // Whether a first result after a pick or flip that raises no doubt is clear enough to
  // take at once: unambiguous, and within the pick search of the pick at the pick's point.
  bool FirstPlaceClear(const RegistrationResult& result) const;
  // How many steps of the walk (slam frame) cross a plan wall under a first place after a
  // pick or flip (path_check); 0 otherwise.
  uint32_t FirstPlaceCrossings(const Se2& T_plan_slam,
                               const std::vector<Eigen::Vector2d>& path_slam) const;
  // Whether T lands within m metres at `at` (default: the wearer) and rad radians of other.
  bool Within(const Se2& T, const Se2& other, double m, double rad,
              const std::optional<Eigen::Vector2d>& at = {}) const;
  // Whether T lands within confirm_m / confirm_rad of an earlier result at the wearer.
  bool Agrees(const Se2& T, const std::optional<Se2>& earlier) const;
  // Whether the results since this place was first seen kept landing on it (confirm_m,
  // confirm_rad) while the wearer walked walk_m; starts over at a new place.
  bool PlaceConfirmed(const RegistrationResult& result, double walk_m);
  // Whether a result beyond the gate explains the cloud's walls and the alignment in use
  // does not (jump_clear_ratio, jump_clear_inliers); scores as in Offer.
  bool ExplainsWallsInstead(const RegistrationResult& result,
                            const std::vector<Eigen::Vector2d>& cloud, double new_score,
                            double old_score) const;
  // Starts the filter over at the alignment in use, as uncertain as a pick at its point
  // (start_pivot_), with this heading variance.
  void StartFilterAtPick(double heading_var);
  // Moves the filter to the wearer, with the drift of the metres walked since.
  void PredictToWearer();
  // The same on a copy: the uncertainty at the wearer now.
  AlignmentFilter FilterAtWearer() const;
  // Clears what the registrations since the last pick told the filter and the
  // reliability features (a new pick or flip starts over).
  void ForgetRegistrations();

  TrackerOptions options_;
  std::shared_ptr<const ClosestWallIndex> index_;
  AlignmentState alignment_;
  uint64_t next_version_ = 1;
  std::optional<Eigen::Vector2d> pick_plan_point_;
  Eigen::Vector2d start_pivot_ = Eigen::Vector2d::Zero();  // of the latest pick or flip
  std::optional<Eigen::Vector2d> last_plan_position_;
  std::optional<Se2> pending_jump_;   // a gated result waiting for later ones to agree
  double pending_walk_m_ = 0;         // walked since it was first seen
  std::optional<Se2> pending_place_;  // where doubted first results keep landing
  double place_walk_m_ = 0;
  int64_t last_start_ns_ = 0;
  std::optional<int64_t> last_global_ns_;
  std::optional<Se2> leading_place_;  // the best place of the latest searches...
  uint32_t lead_count_ = 0;           // ...how many in a row it was ahead (global_min_lead)...
  double lead_product_ = 1;           // ...its leads over them multiplied...
  uint32_t clear_count_ = 0;          // ...and was clear by global_clear_ratio
  bool placement_confirmed_ = true;   // false from a search's place until checks confirm it
  AlignmentFilter filter_;
  std::optional<Eigen::Vector2d> last_slam_position_;
  double last_slam_heading_ = 0;
  double walked_since_predict_m_ = 0;  // not yet in the filter...
  double turned_since_predict_rad_ = 0;
  double walked_since_fused_m_ = 0;
  double walked_since_start_m_ = 0;
  uint32_t fused_ = 0;            // registrations fused since the pick
  double last_disagreement_ = 0;  // sqrt Mahalanobis of the latest registration
  double weakest_direction_ = 0;
  std::vector<AlignmentState> history_;
  // Fit of the alignment in use on the latest registration cloud.
  std::optional<RegistrationResult> current_fit_;
  bool restored_ = false;       // the alignment in use came from a saved state
  bool floor_changed_ = false;  // ...was carried to another floor, not checked there yet
  uint32_t crossings_ = 0;      // steps of the path through a plan wall under the alignment, or
                                // of the walk under a first place refused for them (Offer)
};

// The state an estimator is in: waiting for a plan or an alignment, else as its flag says.
TrackState StateOf(bool has_plan, bool has_alignment, ReliabilityFlag flag);

const char* ToString(ReliabilityFlag flag);
const char* ToString(TrackState state);

}  // namespace floorpose
