#include "core/tracking/mcl.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace floorpose::tracking {
namespace {

// The walk kept for the next update: the last minute of poses (a belief seeded by a
// search weighs the walk that led there; updates that stall keep the latest).
constexpr size_t kMaxPath = 200;

}  // namespace

MclTracker::MclTracker(MclOptions options) : options_(std::move(options)) {}

void MclTracker::SetPlan(std::shared_ptr<const ClosestWallIndex> index) {
  index_ = std::move(index);
  if (index_)
    recovery_ = Recovery(options_.recovery, options_.measurement, *index_,
                         options_.publish.within_m, kPlaceRad);
  Reset();
}

void MclTracker::ChangeFloor(std::shared_ptr<const ClosestWallIndex> index) {
  // The same x-y frame: the belief stays, but is checked on the new floor's walls.
  index_ = std::move(index);
  if (!index_) return Reset();
  alignment_.version = next_version_++;
  ++belief_version_;
  start_.checked = false;
  last_update_ns_.reset();
  recovery_ = Recovery(options_.recovery, options_.measurement, *index_, options_.publish.within_m,
                       kPlaceRad);  // this floor's walls
}

void MclTracker::Reset() {
  belief_.Clear();
  ++belief_version_;
  alignment_ = {};
  pick_plan_point_.reset();
  last_update_ns_.reset();
  last_search_ns_.reset();
  start_.checked = false;
  places_ = 0;
  recovery_.Reset();
}

void MclTracker::StartBelief(const Se2& published, AlignmentSource source, int64_t stamp_ns) {
  ++belief_version_;
  alignment_.T_plan_slam = published;
  alignment_.version = next_version_++;
  alignment_.source = source;
  alignment_.stamp_ns = stamp_ns;
  alignment_.registration.reset();
  last_update_ns_.reset();
  start_.checked = start_.settled = false;
  start_.stamp_ns = stamp_ns;
  places_ = 1;
  recovery_.Reset();
  belief_.Normalize();
}

std::string MclTracker::ApplyWallPick(const WallPick& pick, int64_t stamp_ns) {
  if (!index_) return "no floor plan loaded";
  const auto T = AlignFromWallPick(pick);
  if (!T) return "wall pick needs finite points and non-zero normals";
  pick_plan_point_ = pick.plan_point;
  belief_.Clear();
  belief_.AddGaussian(*T, PlaceCovariance(options_.pick_sigma_m, options_.pick_sigma_rad),
                      pick.plan_point, options_.samples.max_samples, 0.0, rng_);
  StartBelief(*T, AlignmentSource::kWallPick, stamp_ns);
  return {};
}

std::string MclTracker::Flip(int64_t stamp_ns) {
  if (!has_alignment()) return "no alignment to flip";
  const Eigen::Vector2d pivot = pick_plan_point_.value_or(
      alignment_.T_plan_slam * odometry_.position.value_or(Eigen::Vector2d::Zero()));
  const Se2 flip{M_PI, 2.0 * pivot};
  for (Sample& s : belief_.samples()) s.T_plan_slam = flip * s.T_plan_slam;
  StartBelief(flip * alignment_.T_plan_slam, AlignmentSource::kFlip, stamp_ns);
  return {};
}

PlanPoseEstimate MclTracker::Correct(const Pose2& pose_slam, int64_t stamp_ns) {
  const bool gap =
      odometry_.stamp_ns &&
      static_cast<double>(stamp_ns - *odometry_.stamp_ns) * 1e-9 > options_.motion.lost_after_s;
  odometry_.stamp_ns = stamp_ns;
  if (pose_slam.position.allFinite()) {
    if (gap || odometry_.lost) {
      Relocalize(pose_slam.position, stamp_ns);
    } else if (odometry_.position) {
      const double step = (pose_slam.position - *odometry_.position).norm();
      // Steps over 5 m between poses 0.3 s apart are a SLAM relocalisation, not a walk.
      if (step < 5.0) {
        const double turn = std::isfinite(pose_slam.heading)
                                ? WrapAngle(pose_slam.heading - odometry_.heading)
                                : 0.0;
        odometry_.walked_m += step;
        odometry_.turned_rad += turn;
        // The belief drifts with every step, about where each sample puts the wearer.
        const Eigen::Vector2d sigmas = options_.motion.Sigmas(step, turn);
        for (Sample& s : belief_.samples())
          s.T_plan_slam = options_.motion.Sample(s.T_plan_slam, s.T_plan_slam * pose_slam.position,
                                                 sigmas, rng_);
      } else {
        odometry_.path.clear();  // not a step the wearer walked
      }
    }
    odometry_.position = pose_slam.position;
    if (odometry_.path.size() >= kMaxPath) odometry_.path.erase(odometry_.path.begin());
    odometry_.path.push_back(pose_slam.position);
    if (std::isfinite(pose_slam.heading)) odometry_.heading = pose_slam.heading;
  }
  return Project(pose_slam);
}

void MclTracker::Relocalize(const Eigen::Vector2d& wearer_slam, int64_t stamp_ns) {
  odometry_.lost = false;
  odometry_.path.clear();  // of the old frame
  frame_since_ns_ = stamp_ns;
  if (belief_.empty()) return;
  const Eigen::Vector2d sigmas(options_.motion.relocalization_rad,
                               options_.motion.relocalization_m);
  belief_.Draw(options_.samples.max_samples, rng_);
  for (Sample& s : belief_.samples())
    s.T_plan_slam =
        options_.motion.Sample(s.T_plan_slam, s.T_plan_slam * wearer_slam, sigmas, rng_);
  ++belief_version_;  // an update running on the belief from before is void
  last_update_ns_.reset();
  start_.checked = start_.settled = false;
  start_.stamp_ns = stamp_ns;
  recovery_.Relocalized();
}

BeliefSummary MclTracker::Summary(const Eigen::Vector2d& wearer_slam, const Se2& T) const {
  BeliefSummary s;
  s.mass_within = belief_.MassWithin(wearer_slam, T * wearer_slam, options_.publish.within_m);
  s.elsewhere = recovery_.Elsewhere();
  s.fit_ratio = recovery_.FitRatio();
  s.fits = recovery_.Fits();
  s.searched = recovery_.searched();
  s.crowded = recovery_.Unheld() >= 0.5 * s.elsewhere;
  s.places = places_;
  s.checked = start_.checked;
  return s;
}

PlanPoseEstimate MclTracker::Project(const Pose2& pose_slam) const {
  PlanPoseEstimate out;
  out.alignment_version = alignment_.version;
  if (!has_alignment()) {
    out.pose = pose_slam;
    out.reliability = CurrentReliability();
    return out;
  }
  out.pose = Apply(alignment_.T_plan_slam, pose_slam);
  out.reliability =
      pose_slam.position.allFinite()
          ? Assess(Summary(pose_slam.position, alignment_.T_plan_slam), options_.publish)
          : CurrentReliability();
  return out;
}

Reliability MclTracker::CurrentReliability() const {
  Reliability r;
  if (!index_) {
    r.reason = "no floor plan";
    return r;
  }
  if (!has_alignment()) {
    if (belief_.empty()) {
      r.reason = "no alignment: searching the plan";
    } else {
      char text[96];
      std::snprintf(text, sizeof text, "no alignment: %zu place(s) fit, none yet at %.0f%%",
                    places_, 100 * options_.publish.degraded);
      r.reason = text;
    }
    return r;
  }
  return AssessAtWearer();
}

Reliability MclTracker::AssessAtWearer() const {
  return Assess(
      Summary(odometry_.position.value_or(Eigen::Vector2d::Zero()), alignment_.T_plan_slam),
      options_.publish);
}

TrackState MclTracker::state() const {
  return StateOf(has_plan(), has_alignment(), CurrentReliability().flag);
}

TrackerState MclTracker::SaveState() const {
  TrackerState s;
  s.alignment = alignment_;
  s.alignment.registration.reset();
  s.next_version = next_version_;
  const Eigen::Vector2d wearer = odometry_.position.value_or(Eigen::Vector2d::Zero());
  s.pivot = alignment_.T_plan_slam * wearer;
  s.P = belief_.empty() ? PlaceCovariance(options_.pick_sigma_m, options_.pick_sigma_rad)
                        : belief_.Covariance(alignment_.T_plan_slam, wearer);
  if (pick_plan_point_) s.pick_plan_point = *pick_plan_point_;
  s.samples = belief_.samples();
  s.elsewhere = recovery_.Elsewhere();
  s.checked = start_.checked && recovery_.searched();
  return s;
}

std::string MclTracker::RestoreState(const TrackerState& state) {
  if (!index_) return "no floor plan";
  const AlignmentState& a = state.alignment;
  if (!std::isfinite(a.T_plan_slam.theta) || !a.T_plan_slam.t.allFinite() || !state.P.allFinite() ||
      !state.pivot.allFinite() || (state.pick_plan_point && !state.pick_plan_point->allFinite()))
    return "values that are not finite";
  if (a.version == 0 || state.next_version <= a.version)
    return "no alignment, or versions out of order";
  const Eigen::Matrix3d sym = 0.5 * (state.P + state.P.transpose());
  if ((state.P - sym).norm() > 1e-9 * (1 + state.P.norm()) ||
      Eigen::LLT<Eigen::Matrix3d>(sym).info() != Eigen::Success)
    return "a covariance that is not symmetric and positive";
  for (const Sample& sample : state.samples)
    if (!std::isfinite(sample.T_plan_slam.theta) || !sample.T_plan_slam.t.allFinite() ||
        !std::isfinite(sample.log_weight))
      return "belief samples that are not finite";
  if (state.samples.size() > 10 * options_.samples.max_samples)
    return "more belief samples than samples.max_samples allows";
  belief_.Clear();
  if (state.samples.empty()) {
    // At least the drift of a restart's few metres: the belief was at the wearer then.
    const Eigen::Matrix3d P =
        sym + PlaceCovariance(options_.place_sigma_m, options_.place_sigma_rad);
    belief_.AddGaussian(a.T_plan_slam, P, state.pivot, options_.samples.max_samples, 0.0, rng_);
  }
  next_version_ = state.next_version;
  pick_plan_point_ = state.pick_plan_point;
  StartBelief(a.T_plan_slam, a.source, a.stamp_ns);
  // The samples as saved, bit for bit: normalizing them again (StartBelief) moves the last
  // bits of unequal weights, and the restored daemon would not go on exactly as before.
  if (!state.samples.empty()) belief_.samples() = state.samples;
  if (state.checked && state.elsewhere >= 0 && state.elsewhere <= 1) {
    // A belief the walls and a search had checked resumes as it was, under its version.
    alignment_.version = a.version;
    next_version_ = state.next_version;
    start_.checked = true;
    recovery_.Resume(state.elsewhere);
  }
  return {};
}

bool MclTracker::UpdateDue(int64_t now_ns, size_t window_points) const {
  if (!index_ || belief_.empty() || window_points < options_.min_points) return false;
  return !last_update_ns_ ||
         static_cast<double>(now_ns - *last_update_ns_) * 1e-9 >= options_.update_interval_s;
}

MclUpdate MclTracker::PrepareUpdate(int64_t now_ns) {
  MclUpdate u;
  u.belief = belief_;
  u.wearer_slam = odometry_.position.value_or(Eigen::Vector2d::Zero());
  // The first update after a start or a loss weighs the window as a whole one, however few
  // seconds of walls it holds: it settles a relocalized frame in a few seconds. (Weighing
  // only the seconds the frame holds flags a wrong pick sooner, and trusts a relocalized
  // frame later and more often wrongly: docs/evaluation.md, "Why these defaults".)
  u.dt_s =
      last_update_ns_ ? static_cast<double>(now_ns - *last_update_ns_) * 1e-9 : options_.window_s;
  u.evidence = std::clamp(u.dt_s / options_.window_s, 0.0, 1.0);
  u.mid_fit = recovery_.MidFit();
  u.elsewhere = recovery_.Elsewhere();
  u.seed = rng_.Next();
  u.belief_version = belief_version_;
  // The place in use stays until another holds twice its mass and the belief would trust
  // it, or the place in use has lost its samples (PublishedMode); a search's seed is its
  // best place, published or not yet.
  if (!belief_.empty()) u.published = alignment_.T_plan_slam;
  // From here: the walk since prepared, from where the wearer is.
  u.path_slam = std::move(odometry_.path);
  odometry_.path.clear();
  if (odometry_.position) odometry_.path.push_back(*odometry_.position);
  odometry_.walked_m = odometry_.turned_rad = 0;
  last_update_ns_ = now_ns;
  return u;
}

bool MclTracker::FinishUpdate(MclUpdateResult result, int64_t stamp_ns) {
  if (result.belief_version != belief_version_ || result.belief.empty()) return false;
  belief_ = std::move(result.belief);
  // The drift of the walk since the update was prepared (none when it ran inline).
  const Eigen::Vector2d sigmas = options_.motion.Sigmas(odometry_.walked_m, odometry_.turned_rad);
  if (sigmas.squaredNorm() > 0)
    for (Sample& s : belief_.samples())
      s.T_plan_slam = options_.motion.Sample(
          s.T_plan_slam, s.T_plan_slam * odometry_.position.value_or(Eigen::Vector2d::Zero()),
          sigmas, rng_);
  recovery_.Observe(result.fit, result.predictive_fit, result.exponent, result.dt_s);
  places_ = result.places;
  start_.checked = true;
  if (recovery_.relocalized() && !recovery_.searched()) {  // only SearchDue's check reads it
    // The published place's spread, out to twice a place's extent, against a searched place's.
    const Eigen::Matrix3d spread = belief_.CovarianceNear(
        result.published, odometry_.position.value_or(Eigen::Vector2d::Zero()),
        2 * options_.publish.within_m, 2 * kPlaceRad);
    start_.settled =
        spread.determinant() <=
        PlaceCovariance(options_.place_sigma_m, options_.place_sigma_rad).determinant();
  }
  alignment_.T_plan_slam = result.published;
  // A search's seed is published once its place is at least DEGRADED: before, the belief
  // is a guess among places, and a minimap that shows the wearer at one misleads.
  if (alignment_.version == 0 && AssessAtWearer().probability < options_.publish.degraded)
    return true;
  alignment_.version = next_version_++;
  alignment_.source = AlignmentSource::kRegistration;
  alignment_.stamp_ns = stamp_ns;
  alignment_.registration = result.icp;
  return true;
}

bool MclTracker::SearchDue(int64_t now_ns, size_t window_points) const {
  if (!index_ || window_points < options_.search_min_points) return false;
  const double since_s = last_search_ns_ ? static_cast<double>(now_ns - *last_search_ns_) * 1e-9
                                         : std::numeric_limits<double>::infinity();
  if (since_s < options_.recovery.search_interval_s) return false;
  if (belief_.empty()) return true;
  if (!start_.checked) return false;
  if (!recovery_.searched()) {
    // A start is checked against the whole plan: a pick or a place at once (it is doubted
    // at start_doubt), a relocalized frame once the walls have settled the belief in it, or
    // as soon as the doubt since the loss asks.
    if (!recovery_.relocalized() || start_.settled) return true;
    const double since_start_s = static_cast<double>(now_ns - start_.stamp_ns) * 1e-9;
    return recovery_.SearchDue(std::min(since_s, since_start_s));
  }
  return recovery_.SearchDue(since_s);
}

}  // namespace floorpose::tracking
