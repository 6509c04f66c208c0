#include "core/tracker.h"

#include <algorithm>
#include <cmath>

namespace floorpose {

std::optional<Se2> AlignFromWallPick(const WallPick& pick) {
  if (!pick.slam_normal.allFinite() || !pick.plan_normal.allFinite() ||
      !pick.slam_point.allFinite() || !pick.plan_point.allFinite() ||
      pick.slam_normal.norm() < 1e-6 || pick.plan_normal.norm() < 1e-6) {
    return std::nullopt;
  }
  // theta = angle from n_measure to n_ref (eq. 6.2; in 2D the axis is always z).
  Se2 T;
  T.theta = WrapAngle(std::atan2(pick.plan_normal.y(), pick.plan_normal.x()) -
                      std::atan2(pick.slam_normal.y(), pick.slam_normal.x()));
  T.t = pick.plan_point - T.R() * pick.slam_point;  // T = x_ref - R x_measure
  return T;
}

RegistrationOptions ToRegistrationOptions(const TrackerOptions& t, AlignmentSource from) {
  RegistrationOptions r;
  r.method = t.method;
  r.icp = t.icp;
  r.hough = t.hough;
  r.wall_buffer_m = t.wall_buffer_m;
  r.clip_margin_m = t.clip_margin_m;
  if (from == AlignmentSource::kWallPick || from == AlignmentSource::kFlip) {
    r.search_window_m = t.pick_search_m;
    r.search_window_rad = t.pick_search_rad;
  }
  return r;
}

void Tracker::SetPlan(std::shared_ptr<const ClosestWallIndex> index) {
  index_ = std::move(index);
  Reset();
}

void Tracker::Reset() {
  alignment_ = {};
  pending_jump_.reset();
  pick_plan_point_.reset();
  last_plan_position_.reset();
  current_fit_.reset();
  last_start_ns_ = 0;
}

void Tracker::SetAlignment(const Se2& T, AlignmentSource source, int64_t stamp_ns) {
  pending_jump_.reset();
  alignment_.T_plan_slam = T;
  alignment_.version = next_version_++;
  alignment_.source = source;
  alignment_.stamp_ns = stamp_ns;
  alignment_.registration.reset();
}

std::string Tracker::ApplyWallPick(const WallPick& pick, int64_t stamp_ns) {
  if (!index_) return "no floor plan loaded";
  const auto T = AlignFromWallPick(pick);
  if (!T) return "wall pick needs finite points and non-zero normals";
  SetAlignment(*T, AlignmentSource::kWallPick, stamp_ns);
  pick_plan_point_ = pick.plan_point;
  current_fit_.reset();
  return {};
}

std::string Tracker::Flip(int64_t stamp_ns) {
  if (!has_alignment()) return "no alignment to flip";
  const std::optional<Eigen::Vector2d> pivot =
      pick_plan_point_ ? pick_plan_point_ : last_plan_position_;
  if (!pivot) return "no pivot: neither a wall pick nor a pose yet";
  // Rotation by pi about the pivot: p -> 2 pivot - p.
  const Se2 flip{M_PI, 2.0 * *pivot};
  SetAlignment(flip * alignment_.T_plan_slam, AlignmentSource::kFlip, stamp_ns);
  current_fit_.reset();
  return {};
}

PlanPoseEstimate Tracker::Correct(const Pose2& pose_slam) {
  PlanPoseEstimate out;
  out.alignment_version = alignment_.version;
  out.reliability = CurrentReliability();
  if (!has_alignment()) {
    out.pose = pose_slam;  // slam coordinates, flagged unreliable
    return out;
  }
  out.pose = Apply(alignment_.T_plan_slam, pose_slam);
  last_plan_position_ = out.pose.position;
  return out;
}

bool Tracker::RegistrationDue(int64_t now_ns, size_t live_points, size_t new_points) const {
  if (!index_ || !has_alignment() || live_points < options_.min_points || new_points == 0)
    return false;
  if (new_points >= options_.min_new_points) return true;
  return static_cast<double>(now_ns - last_start_ns_) * 1e-9 >= options_.max_interval_s;
}

Tracker::Decision Tracker::Offer(const RegistrationResult& result,
                                 const std::vector<Eigen::Vector2d>& cloud,
                                 uint64_t based_on_version, int64_t stamp_ns) {
  Decision d;
  if (!index_ || !has_alignment()) {
    d.reason = "no alignment any more";
    return d;
  }
  if (based_on_version != alignment_.version) {
    d.reason = "alignment changed while registering";
    return d;
  }
  // Re-score the alignment in use on the same cloud, so both fits are comparable.
  // Distances are capped at the inlier threshold: with a 1.5 m cap, clutter far from the
  // walls outweighs the walls and can prefer a pose 10-20 cm off.
  const IcpOptions& o = options_.icp;
  const double cap = options_.score_cap_m > 0 ? options_.score_cap_m : o.max_correspondence_m;
  RegistrationResult old_fit;
  double old_score = 0, new_score = 0;
  EvaluateFit(cloud, *index_, alignment_.T_plan_slam, cap, o.inlier_threshold_m, nullptr,
              &old_score);
  EvaluateFit(cloud, *index_, alignment_.T_plan_slam, o.max_correspondence_m, o.inlier_threshold_m,
              &old_fit, nullptr);
  EvaluateFit(cloud, *index_, result.T_plan_slam, cap, o.inlier_threshold_m, nullptr, &new_score);
  if (!result.T_plan_slam.t.allFinite() || !std::isfinite(result.T_plan_slam.theta)) {
    d.reason = "non-finite result";
  } else if (result.matched < 3) {
    d.reason = "registration failed: " + result.reason;
  } else if (!(new_score < old_score)) {
    d.reason = "fit not better than the alignment in use";
  } else {
    d.accepted = true;
  }
  if (d.accepted && alignment_.source == AlignmentSource::kRegistration && options_.jump_m > 0) {
    // A registered alignment does not jump on one result's word (the navigation app's
    // 3 m / 10 degree rule): a far move must be found again by the next registration.
    const Eigen::Vector2d pivot = last_plan_position_.value_or(Eigen::Vector2d::Zero());
    auto moves = [&](const Se2& from, const Se2& to, double* metres, double* radians) {
      *metres = (to * (from.Inverse() * pivot) - pivot).norm();
      *radians = std::abs(WrapAngle(to.theta - from.theta));
    };
    double metres = 0, radians = 0;
    moves(alignment_.T_plan_slam, result.T_plan_slam, &metres, &radians);
    if (metres > options_.jump_m || radians > options_.jump_rad) {
      double pm = 1e9, pr = 1e9;
      if (pending_jump_) moves(*pending_jump_, result.T_plan_slam, &pm, &pr);
      if (pm > 0.5 || pr > 0.035) {
        pending_jump_ = result.T_plan_slam;
        d.accepted = false;
        d.reason = "jump of " + std::to_string(metres) + " m / " +
                   std::to_string(radians * 180 / M_PI) + " deg waits for confirmation";
      }
    }
  }
  if (d.accepted) {
    pending_jump_.reset();
    SetAlignment(result.T_plan_slam, AlignmentSource::kRegistration, stamp_ns);
    alignment_.registration = result;
    current_fit_ = result;
  } else {
    old_fit.method = "current";
    current_fit_ = old_fit;
  }
  return d;
}

Reliability Tracker::CurrentReliability() const {
  Reliability r;
  if (!index_) {
    r.reason = "no floor plan";
    return r;
  }
  if (!has_alignment()) {
    r.reason = "no alignment: waiting for a wall pick";
    return r;
  }
  if (!current_fit_) {
    r.flag = ReliabilityFlag::kDegraded;
    r.probability = 0.5;
    r.reason = alignment_.source == AlignmentSource::kFlip ? "flipped, not yet checked"
                                                           : "wall pick, not yet checked";
    return r;
  }
  const RegistrationResult& f = *current_fit_;
  const double ratio = f.points ? static_cast<double>(f.inliers) / f.points : 0.0;
  const double q = f.inlier_rmse / options_.reliable_rmse_m;
  // Heuristic until issue "Tracking" calibrates it on simulated walks.
  r.probability = std::clamp(ratio, 0.0, 1.0) * std::exp(-0.5 * q * q);
  r.rmse_m = f.inlier_rmse;
  if (ratio < 0.2) {
    r.flag = ReliabilityFlag::kUnreliable;
    r.reason = "few wall points match the plan";
  } else if (ratio < options_.reliable_inlier_ratio) {
    r.flag = ReliabilityFlag::kDegraded;
    r.reason = "low inlier ratio";
  } else if (f.inlier_rmse > options_.reliable_rmse_m) {
    r.flag = ReliabilityFlag::kDegraded;
    r.reason = "high inlier RMSE";
  } else {
    r.flag = ReliabilityFlag::kReliable;
    r.reason = "registered";
  }
  return r;
}

TrackState Tracker::state() const {
  if (!index_) return TrackState::kWaitingForPlan;
  if (!has_alignment()) return TrackState::kWaitingForAlignment;
  switch (CurrentReliability().flag) {
    case ReliabilityFlag::kReliable: return TrackState::kTracking;
    case ReliabilityFlag::kDegraded: return TrackState::kDegraded;
    case ReliabilityFlag::kUnreliable: return TrackState::kLost;
  }
  return TrackState::kLost;
}

const char* ToString(ReliabilityFlag flag) {
  switch (flag) {
    case ReliabilityFlag::kReliable: return "RELIABLE";
    case ReliabilityFlag::kDegraded: return "DEGRADED";
    case ReliabilityFlag::kUnreliable: return "UNRELIABLE";
  }
  return "?";
}

const char* ToString(TrackState state) {
  switch (state) {
    case TrackState::kWaitingForPlan: return "WAITING_FOR_PLAN";
    case TrackState::kWaitingForAlignment: return "WAITING_FOR_ALIGNMENT";
    case TrackState::kTracking: return "TRACKING";
    case TrackState::kDegraded: return "DEGRADED";
    case TrackState::kLost: return "LOST";
  }
  return "?";
}

}  // namespace floorpose
