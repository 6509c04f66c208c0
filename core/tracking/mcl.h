// Monte Carlo localization of the alignment T_plan_slam (config `tracking`): one belief that can
// hold several places, moved by the SLAM's drift (MotionModel), weighted by how the recent wall
// points fit the plan (MeasurementModel), resampled to as many samples as it needs (Belief),
// reseeded from searches of the whole plan when the walls stop fitting (Recovery), and published
// with the share of its mass near the published pose (Assess). ICP polishes the published place
// to centimetres. A wall pick and a flip are priors for the belief; without one, a search of the
// plan seeds it.
//
// The daemon and the tools drive it: poses on the io thread, updates prepared there, run
// on a worker (RunMclUpdate, update.cc), and finished back there.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/closest_wall_index.h"
#include "core/global_search.h"
#include "core/registration.h"
#include "core/tracking/alignment.h"
#include "core/tracking/belief.h"
#include "core/tracking/measurement_model.h"
#include "core/tracking/motion_model.h"
#include "core/tracking/recovery.h"
#include "core/tracking/reliability.h"

namespace floorpose::tracking {

// Samples within publish.within_m at the wearer and this in heading are one place.
constexpr double kPlaceRad = 10.0 * M_PI / 180;
// The least share of the belief a place offered to it gets: a search's place the belief
// does not hold, or the place ICP reaches from the leading one (RunMclUpdate).
constexpr double kOfferShare = 0.05;

struct MclOptions {
  MotionModel motion;
  MeasurementModel measurement;
  SampleBounds samples;
  RecoveryOptions recovery;
  PublishOptions publish;
  double window_s = 20.0;                    // the wall points of the last this many seconds weigh
  double update_interval_s = 1.0;            // an update this often while walls come, seconds
  uint32_t min_points = 50;                  // ...with at least this many wall points in the window
  size_t weigh_points = 300;                 // thinned (0.1 m voxels) to at most this many to weigh
  double pick_sigma_m = 1.5;                 // a wall pick's uncertainty at its point, metres...
  double pick_sigma_rad = 5.0 * M_PI / 180;  // ...and of its heading
  double place_sigma_m = 0.3;                // a searched place's, metres...
  double place_sigma_rad = 2.0 * M_PI / 180;  // ...and radians
  uint32_t search_min_points = 150;           // a search of the plan needs this many points...
  double search_window_s = 60.0;              // ...over the walls of this many seconds
  // How a search's places are refined and ranked (RefinePlaces); the belief takes those of
  // rank 0 and 1. Wall points scored to 0.2 m; steps through plan walls 0.4 m clear of
  // their ends count (each costs a place motion.through_wall, PlaceLogWeights); points
  // hidden from the path within 4.5 m and plan walls unseen within 2 m of it count as
  // misses; places fitting under 45% of the walls rank last.
  RefineOptions refine = [] {
    RefineOptions r;
    r.cap_m = 0.2;
    r.path_margin_m = 0.4;
    r.min_inliers = 0.45;
    r.sight_reach_m = 4.5;
    r.unseen_reach_m = 2.0;
    r.unseen_allowance = 0.5;
    r.alike_reach_m = 4.5;
    return r;
  }();
  IcpOptions icp;
};

// An update to run: a copy of the belief and what moves and weighs it.
struct MclUpdate {
  Belief belief;
  Eigen::Vector2d wearer_slam = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> path_slam;  // the wearer's walk since the last update
  // The window's wall points that came since the last update (none: the whole window).
  std::vector<Eigen::Vector2d> fresh_slam;
  // The wearer's positions over the window, up to where the mesh around them has come
  // (kMeshLatencyS): where plan walls in sight should show (SightLogLikelihood).
  std::vector<Eigen::Vector2d> sight_slam;
  double evidence = 0;  // the tempering exponent: the window's share that is new
  // A fit per point above this is nearer a right place's than a random one's
  // (Recovery::MidFit).
  double mid_fit = 0;
  double elsewhere = 0;  // Recovery::Elsewhere when prepared
  double dt_s = 0;
  uint64_t seed = 0;
  uint64_t belief_version = 0;
  std::optional<Se2> published;  // the alignment published now, if any
};

struct MclUpdateResult {
  Belief belief;
  Se2 published;
  double fit = 0;             // the belief's mean log-likelihood per point (before weighing)
  double predictive_fit = 0;  // ...its predictive likelihood per point (BeliefFit)
  double exponent = 0;        // ...and the tempering exponent it was weighed with
  double mode_mass = 0;       // of the published place
  size_t places = 0;          // places holding at least 5% of the belief
  RegistrationResult icp;     // the polish of the published place
  bool polished = false;      // ...taken
  bool offered = false;       // ...or the place it reached offered to the belief
  double dt_s = 0;
  uint64_t belief_version = 0;
};

// Moves, weighs, resamples and polishes; touches nothing but its arguments.
MclUpdateResult RunMclUpdate(MclUpdate update, const std::vector<Eigen::Vector2d>& cloud,
                             const ClosestWallIndex& index, const MclOptions& options);

class MclTracker {
 public:
  explicit MclTracker(MclOptions options);

  void SetPlan(std::shared_ptr<const ClosestWallIndex> index);
  void ChangeFloor(std::shared_ptr<const ClosestWallIndex> index);
  void Reset();

  bool has_plan() const { return index_ != nullptr; }
  const std::shared_ptr<const ClosestWallIndex>& index() const { return index_; }
  bool has_alignment() const { return alignment_.version > 0; }
  const AlignmentState& alignment() const { return alignment_; }
  const MclOptions& options() const { return options_; }
  // The device's drift and the window its walls stay rigid over: a headset's, or a
  // wheel's (tracking.wheel) once its poses say WHEEL.
  void SetDrift(const MotionModel& motion, double window_s) {
    options_.motion = motion;
    options_.window_s = window_s;
  }
  const Belief& belief() const { return belief_; }

  std::string ApplyWallPick(const WallPick& pick, int64_t stamp_ns);
  std::string Flip(int64_t stamp_ns);

  // A pose the headset tracked, at stamp_ns: the belief drifts with the step from the
  // last, or spreads by the relocalization model after a loss of tracking.
  PlanPoseEstimate Correct(const Pose2& pose_slam, int64_t stamp_ns);
  // The headset says it lost tracking: its next pose may be in a jumped frame.
  void LoseTracking() { odometry_.lost = true; }
  // The wall points since this stamp are in the SLAM frame of now (after the last loss).
  int64_t frame_since_ns() const { return frame_since_ns_; }
  PlanPoseEstimate Project(const Pose2& pose_slam) const;
  TrackState state() const;
  Reliability CurrentReliability() const;

  TrackerState SaveState() const;
  std::string RestoreState(const TrackerState& state);

  // An update is due with a belief, min_points in the window, and update_interval_s
  // since the last.
  bool UpdateDue(int64_t now_ns, size_t window_points) const;
  std::optional<int64_t> last_update_ns() const { return last_update_ns_; }
  MclUpdate PrepareUpdate(int64_t now_ns);
  // Takes an update's belief when no pick, flip, place or reset came since it was
  // prepared; returns whether it did. A search's seed publishes no place until its place
  // is at least DEGRADED (publish.degraded).
  bool FinishUpdate(MclUpdateResult result, int64_t stamp_ns);

  // A search of the whole plan is due without a belief, once after every start (pick,
  // flip, place, restore, relocalization) to check it, and then at a rate in proportion to
  // the chance that the wearer is elsewhere (RecoveryOptions::search_share); at most every
  // search_interval_s. A relocalized frame is checked once the walls have settled the
  // belief in it, or as soon as the doubt since the loss asks: a place a search finds is
  // drawn compact, and outweighs a spread belief of the same fit on its spread alone.
  bool SearchDue(int64_t now_ns, size_t window_points) const;
  void MarkSearchStarted(int64_t now_ns) { last_search_ns_ = now_ns; }
  // Seeds the belief with a search's refined places (RefinePlaces' order), or mixes them
  // into it as recovery does (offer.cc); returns what it did. `cloud_slam`, the walls the search
  // ran on, weigh the places against one another (PlaceLogWeights).
  std::string OfferPlaces(const std::vector<GlobalPlace>& places,
                          const std::vector<Eigen::Vector2d>& cloud_slam, int64_t stamp_ns);

 private:
  // A new belief from a prior (pick, flip, place, restore): a new alignment version, and
  // nothing of the old belief's fit.
  void StartBelief(const Se2& published, AlignmentSource source, int64_t stamp_ns);
  BeliefSummary Summary(const Eigen::Vector2d& wearer_slam, const Se2& T) const;
  // The alignment in use, assessed where the wearer is now.
  Reliability AssessAtWearer() const;
  // `unheld`: the share of a seed's mass the places that fit and it could not take would
  // have (Recovery::Searched).
  std::string MixPlaces(const std::vector<GlobalPlace>& places,
                        const std::vector<Eigen::Vector2d>& cloud_slam, int64_t stamp_ns,
                        double& unheld);
  // The log-likelihood of the search's walls at each place, one window's worth
  // (independent_points): those walls chose the places, so they tell nothing of whether
  // the wearer is at any of them (the best of many random places fits them well too), but
  // among the places found the right one fits them better than a look-alike. Plus the
  // price of the wearer's walk there (motion.through_wall a plan wall walked through,
  // GlobalPlace::path_crossings), as every step after the search pays it. Relative to
  // the best place.
  std::vector<double> PlaceLogWeights(const std::vector<const GlobalPlace*>& places,
                                      const std::vector<Eigen::Vector2d>& cloud_slam) const;

  MclOptions options_;
  std::shared_ptr<const ClosestWallIndex> index_;
  Belief belief_;
  uint64_t belief_version_ = 0;
  Recovery recovery_;
  AlignmentState alignment_;
  uint64_t next_version_ = 1;
  SplitMix64 rng_{0x6d636c};
  // After a loss of tracking, the frame may have jumped: the belief spreads and the walls
  // from before stop weighing.
  void Relocalize(const Eigen::Vector2d& wearer_slam, int64_t stamp_ns);

  struct Odometry {  // the wearer now, and the walk since the last update was prepared
    std::optional<Eigen::Vector2d> position;
    double heading = 0, walked_m = 0, turned_rad = 0;
    std::vector<Eigen::Vector2d> path;  // positions since the last update was prepared
    std::optional<int64_t> stamp_ns;    // of the last pose
    bool lost = false;                  // the headset said it lost tracking since
  } odometry_;
  int64_t frame_since_ns_ = INT64_MIN;
  std::optional<Eigen::Vector2d> pick_plan_point_;
  std::optional<int64_t> last_update_ns_, last_search_ns_;
  size_t places_ = 0;  // of the latest update
  struct Start {       // the last start (pick, flip, place, restore) or relocalization
    int64_t stamp_ns = 0;
    bool checked = false;  // an update weighed the belief since
    // Its leading place is no more spread than a searched place is drawn (by the volume
    // of its covariance): a search's places and the belief's own are weighed alike.
    bool settled = false;
  } start_;
};

}  // namespace floorpose::tracking
