#include "core/tracker.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

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

RegistrationOptions ToRegistrationOptions(const TrackerOptions& t, AlignmentSource from,
                                          const std::optional<Eigen::Vector2d>& pivot) {
  RegistrationOptions r;
  r.method = t.method;
  r.icp = t.icp;
  r.hough = t.hough;
  r.wall_buffer_m = t.wall_buffer_m;
  r.clip_margin_m = t.clip_margin_m;
  if (from == AlignmentSource::kWallPick || from == AlignmentSource::kFlip ||
      from == AlignmentSource::kGlobalSearch) {
    r.search_window_m = t.pick_search_m;
    r.search_window_rad = t.pick_search_rad;
    r.search_tie_ratio = t.pick_tie_ratio;
    r.search_pivot = pivot;
  }
  return r;
}

AlignmentFilter Tracker::FilterAtWearer() const {
  AlignmentFilter at = filter_;
  if (last_slam_position_)
    at.Predict(alignment_.T_plan_slam * *last_slam_position_, walked_since_predict_m_,
               turned_since_predict_rad_);
  return at;
}

RegistrationOptions Tracker::NextRegistrationOptions() const {
  if (alignment_.source != AlignmentSource::kRegistration)
    return ToRegistrationOptions(options_, alignment_.source, start_pivot_);
  RegistrationOptions r = ToRegistrationOptions(options_, alignment_.source, std::nullopt);
  if (options_.search_sigmas <= 0 || !last_slam_position_) return r;
  const AlignmentFilter at = FilterAtWearer();
  if (options_.search_unexplained && pending_jump_ && current_fit_ && current_fit_->points > 0 &&
      current_fit_->inliers < options_.jump_clear_inliers * current_fit_->points) {
    // A result disagreed and the walls do not fit the alignment in use either: the
    // filter's sigmas no longer say how far off it is.
    r.search_window_m = options_.pick_search_m;
    r.search_window_rad = options_.pick_search_rad;
    r.search_tie_ratio = options_.search_tie_ratio;
    r.search_pivot = at.pivot();
    return r;
  }
  const double m = std::min(options_.pick_search_m, options_.search_sigmas * at.position_sigma_m());
  if (m < options_.search_min_m) return r;
  r.search_window_m = m;
  r.search_window_rad =
      std::min(options_.pick_search_rad, options_.search_sigmas * at.heading_sigma_rad());
  r.search_tie_ratio = options_.search_tie_ratio;
  r.search_pivot = at.pivot();
  r.search_covariance = at.P();
  r.search_max_sigmas = options_.search_sigmas;
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
  restored_ = floor_changed_ = false;
  crossings_ = 0;
  last_start_ns_ = 0;
  last_global_ns_.reset();
  leading_place_.reset();
  lead_count_ = clear_count_ = 0;
  lead_product_ = 1;
  placement_confirmed_ = true;
  walked_since_start_m_ = 0;
  ForgetRegistrations();
  history_.clear();
}

void Tracker::ChangeFloor(std::shared_ptr<const ClosestWallIndex> index) {
  index_ = std::move(index);
  pending_jump_.reset();
  current_fit_.reset();
  crossings_ = 0;
  floor_changed_ = true;
  // A registration running against the floor left is stale when it comes back.
  if (has_alignment()) alignment_.version = next_version_++;
}

void Tracker::ForgetRegistrations() {
  walked_since_predict_m_ = walked_since_fused_m_ = turned_since_predict_rad_ = 0;
  fused_ = 0;
  last_disagreement_ = weakest_direction_ = 0;
  pending_place_.reset();
  place_walk_m_ = 0;
}

void Tracker::SetAlignment(const Se2& T, AlignmentSource source, int64_t stamp_ns) {
  pending_jump_.reset();
  crossings_ = 0;
  restored_ = floor_changed_ = false;
  alignment_.T_plan_slam = T;
  alignment_.version = next_version_++;
  alignment_.source = source;
  alignment_.stamp_ns = stamp_ns;
  alignment_.registration.reset();
  if (source != AlignmentSource::kRegistration) {
    // A pick or a flip: start the filter over, as uncertain as a pick is.
    const Eigen::Vector2d pivot = pick_plan_point_.value_or(
        last_plan_position_.value_or(T * last_slam_position_.value_or(Eigen::Vector2d::Zero())));
    start_pivot_ = pivot;
    StartFilterAtPick(options_.pick_sigma_rad * options_.pick_sigma_rad);
    ForgetRegistrations();
  }
}

void Tracker::StartFilterAtPick(double heading_var) {
  const double sm = options_.pick_sigma_m;
  filter_ = AlignmentFilter(options_.filter);
  filter_.Reset(alignment_.T_plan_slam, Eigen::Vector3d(heading_var, sm * sm, sm * sm).asDiagonal(),
                start_pivot_);
}

void Tracker::PredictToWearer() {
  const Eigen::Vector2d pivot =
      last_slam_position_ ? alignment_.T_plan_slam * *last_slam_position_ : filter_.pivot();
  filter_.Predict(pivot, walked_since_predict_m_, turned_since_predict_rad_);
  walked_since_predict_m_ = turned_since_predict_rad_ = 0;
}

TrackerState Tracker::SaveState() const {
  TrackerState s;
  s.alignment = alignment_;
  s.alignment.registration.reset();
  s.next_version = next_version_;
  s.P = filter_.P();
  s.pivot = filter_.pivot();
  s.drift_scale = filter_.drift_scale();
  s.pick_plan_point = pick_plan_point_;
  s.start_pivot = start_pivot_;
  s.fused = fused_;
  return s;
}

std::string Tracker::RestoreState(const TrackerState& s) {
  if (!index_) return "no floor plan loaded";
  const AlignmentState& a = s.alignment;
  const bool finite = std::isfinite(a.T_plan_slam.theta) && a.T_plan_slam.t.allFinite() &&
                      s.P.allFinite() && s.pivot.allFinite() && s.start_pivot.allFinite() &&
                      (!s.pick_plan_point || s.pick_plan_point->allFinite());
  if (!finite) return "values that are not finite";
  if (a.version == 0 || s.next_version <= a.version)
    return "no alignment, or versions out of order";
  if (!(s.drift_scale >= 1.0 && s.drift_scale <= options_.filter.max_drift_scale))
    return "a drift scale out of range";
  const Eigen::Matrix3d sym = 0.5 * (s.P + s.P.transpose());
  if ((s.P - sym).norm() > 1e-9 * (1 + s.P.norm()) ||
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(sym).eigenvalues()(0) < 0)
    return "a covariance that is not symmetric and positive";
  Reset();
  alignment_ = a;
  alignment_.registration.reset();
  next_version_ = s.next_version;
  pick_plan_point_ = s.pick_plan_point;
  start_pivot_ = s.start_pivot;
  filter_ = AlignmentFilter(options_.filter);
  filter_.Reset(a.T_plan_slam, sym, s.pivot);
  filter_.set_drift_scale(s.drift_scale);
  fused_ = s.fused;
  restored_ = true;
  placement_confirmed_ = true;
  history_.push_back(alignment_);
  return {};
}

std::string Tracker::ApplyWallPick(const WallPick& pick, int64_t stamp_ns) {
  if (!index_) return "no floor plan loaded";
  const auto T = AlignFromWallPick(pick);
  if (!T) return "wall pick needs finite points and non-zero normals";
  pick_plan_point_ = pick.plan_point;
  SetAlignment(*T, AlignmentSource::kWallPick, stamp_ns);
  current_fit_.reset();
  placement_confirmed_ = true;  // the wearer's word; the registrations check it
  return {};
}

bool Tracker::GlobalSearchDue(int64_t now_ns, size_t live_points) const {
  if (!options_.global_search || !index_ || live_points < GlobalMinPoints()) return false;
  if (has_alignment() && placement_confirmed_ && !WallsDoNotFit()) return false;
  // A check runs more often: the wearer is on the plan already, perhaps on a wrong place.
  const double interval =
      has_alignment() ? options_.global_check_interval_s : options_.global_interval_s;
  return !last_global_ns_ || static_cast<double>(now_ns - *last_global_ns_) * 1e-9 >= interval;
}

uint32_t Tracker::GlobalMinPoints() const {
  return has_alignment() ? options_.global_check_min_points : options_.global_min_points;
}

bool Tracker::WallsDoNotFit() const {
  return has_alignment() && current_fit_ && current_fit_->points > 0 &&
         static_cast<double>(current_fit_->inliers) <
             options_.global_min_inliers * static_cast<double>(current_fit_->points);
}

double Tracker::OffPlanM() const {
  if (options_.off_plan_margin_m <= 0 || !index_ || !has_alignment() || !last_slam_position_)
    return 0;
  const FloorPlan& plan = index_->plan();
  const Eigen::Vector2d p = alignment_.T_plan_slam * *last_slam_position_;
  const Eigen::Vector2d outside = (plan.min - p).cwiseMax(p - plan.max).cwiseMax(0.0);
  return std::max(0.0, outside.norm() - options_.off_plan_margin_m);
}

Tracker::Decision Tracker::OfferPlaces(const std::vector<GlobalPlace>& places,
                                       const Eigen::Vector2d& centre_slam,
                                       uint64_t based_on_version, int64_t stamp_ns,
                                       const std::vector<double>& full_grid_scores) {
  Decision d;
  if (!index_) {
    d.reason = "no floor plan loaded";
    return d;
  }
  if (based_on_version != alignment_.version) {
    d.reason = "alignment changed while searching";
    return d;
  }
  std::vector<GlobalPlace> usable;
  for (const GlobalPlace& p : places)
    if (p.T_plan_slam.t.allFinite() && std::isfinite(p.T_plan_slam.theta) &&
        std::isfinite(p.fit_mse))
      usable.push_back(p);
  if (usable.empty() || !centre_slam.allFinite()) {
    lead_count_ = clear_count_ = 0;
    lead_product_ = 1;
    d.reason = "no place fits";
    return d;
  }
  const GlobalPlace& best = usable.front();
  const Eigen::Vector2d centre_plan = best.T_plan_slam * centre_slam;
  auto same_place = [&](const Se2& a, const Se2& b) {
    return Within(a, b, 1.0, 10.0 * M_PI / 180, centre_plan);
  };
  // The best must fit and walk clear (RefinePlaces' rank 0), and beat the next on the
  // walls, whatever the next's walk: a place that alone walks clear of the walls is too
  // often a look-alike in a hall whose true place the search did not return. Its leads
  // (the next's error over its own) multiply over the searches in a row it stays the best
  // by at least global_min_lead; it has led once they reach what global_confirm_searches
  // leads of 1 / global_lead_ratio would. A place a little ahead search after search
  // (a hall whose walls all look alike at a glance) gets there too, only later.
  const double next =
      usable.size() > 1 ? usable[1].fit_mse : std::numeric_limits<double>::infinity();
  const double lead = std::min(next / std::max(best.fit_mse, 1e-12), 1e6);
  // A twin the walls cannot tell from the best: unless the fits differ by far more than
  // the drift makes them, the difference is noise.
  const auto twin = std::find_if(usable.begin() + 1, usable.end(), [&](const GlobalPlace& p) {
    return options_.global_alike_share > 0 && p.rank == 0 &&
           p.alike >= options_.global_alike_share &&
           !(best.fit_mse < options_.global_twin_clear_ratio * p.fit_mse);
  });
  const bool fits = best.rank == 0 && best.inlier_ratio >= options_.global_place_min_inliers &&
                    twin == usable.end();
  // The grid may have left out places as good as those it returned.
  const std::vector<double>& grid = full_grid_scores;
  const bool crowded = options_.global_crowded_ratio > 0 && grid.size() >= 2 &&
                       grid.back() >= options_.global_crowded_ratio * grid.front();
  const bool ahead = fits && !crowded && lead >= options_.global_min_lead;
  const bool clear = fits && !crowded && best.fit_mse < options_.global_clear_ratio * next;
  const bool same = leading_place_ && same_place(best.T_plan_slam, *leading_place_);
  // Still first, but by less than global_min_lead: the streak holds, the search does
  // not count towards it.
  const bool holds = fits && same && lead >= 1.0;
  lead_count_ = ahead ? (same ? lead_count_ : 0) + 1 : holds ? lead_count_ : 0;
  lead_product_ = ahead ? (same ? lead_product_ : 1) * lead : holds ? lead_product_ : 1;
  clear_count_ = clear ? (same ? clear_count_ : 0) + 1 : 0;
  leading_place_ = best.T_plan_slam;
  const uint32_t confirm = options_.global_confirm_searches;
  const double need = std::pow(1 / options_.global_lead_ratio, confirm);
  const bool led = lead_count_ >= confirm && lead_product_ >= need;
  const bool won = clear_count_ >= 2 || led;
  char text[200];
  std::snprintf(text, sizeof text,
                "best fits %.0f%% of the walls, the next's error %.1f times its own; ahead %u "
                "searches in a row, leads multiplying to %.1f (%u and %.1f to win)",
                100 * best.inlier_ratio, lead, lead_count_, lead_product_, confirm, need);
  d.reason = text;
  if (crowded) {
    std::snprintf(text, sizeof text, "; the grid's %zu places all score within %.0f%% of the best",
                  grid.size(), 100 * (1 - grid.back() / grid.front()));
    d.reason += text;
  }
  if (twin != usable.end()) {
    std::snprintf(text, sizeof text,
                  "; a place %.1f m away looks the same from the walk (%.0f%% of the walls in "
                  "sight)",
                  (twin->T_plan_slam * centre_slam - centre_plan).norm(), 100 * twin->alike);
    d.reason += text;
  }

  const bool in_use = has_alignment() && same_place(best.T_plan_slam, alignment_.T_plan_slam);
  if (in_use) {
    if (!placement_confirmed_ && led) {
      placement_confirmed_ = true;
      d.reason = "place confirmed: " + d.reason;
    }
    return d;
  }
  if (has_alignment()) {
    // Another place: it replaces the one in use only when it has led over the checks and
    // fits clearly better (global_clear_ratio); better by a lead (global_lead_ratio) when
    // the walls do not fit the one in use either, as if there were none (a wrong pick).
    const auto current = std::find_if(usable.begin(), usable.end(), [&](const GlobalPlace& p) {
      return same_place(p.T_plan_slam, alignment_.T_plan_slam);
    });
    const double current_mse =
        current != usable.end() ? current->fit_mse : std::numeric_limits<double>::infinity();
    const double better =
        WallsDoNotFit() ? options_.global_lead_ratio : options_.global_clear_ratio;
    if (!led || !(best.fit_mse < better * current_mse)) return d;
    // A confirmed place (or a pick) that the registrations find fitting stays: a place
    // that fits the window a little better is a look-alike, not a recovery.
    if (placement_confirmed_ && !WallsDoNotFit()) {
      d.reason = "the place in use still fits the walls; " + d.reason;
      return d;
    }
    char worse[48] = "nothing";
    if (std::isfinite(current_mse))
      std::snprintf(worse, sizeof worse, "%.1f times worse",
                    current_mse / std::max(best.fit_mse, 1e-12));
    d.reason = std::string("relocated (the place in use fits ") + worse + "): " + d.reason;
  } else if (!won) {
    return d;
  }
  pick_plan_point_ = centre_plan;
  SetAlignment(best.T_plan_slam, AlignmentSource::kGlobalSearch, stamp_ns);
  current_fit_.reset();
  placement_confirmed_ = led;
  d.accepted = true;
  return d;
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
  if (last_slam_position_) {
    // Steps over 5 m between poses 0.3 s apart are a SLAM relocalisation, not a walk.
    const double step = (pose_slam.position - *last_slam_position_).norm();
    if (step < 5.0) {
      walked_since_predict_m_ += step;
      walked_since_fused_m_ += step;
      walked_since_start_m_ += step;
      pending_walk_m_ += step;
      place_walk_m_ += step;
      if (std::isfinite(pose_slam.heading))
        turned_since_predict_rad_ += WrapAngle(pose_slam.heading - last_slam_heading_);
    }
  }
  if (options_.path_check && last_slam_position_ && has_alignment() &&
      pose_slam.position.allFinite() && (pose_slam.position - *last_slam_position_).norm() < 5.0) {
    const Se2& T = alignment_.T_plan_slam;
    if (StepCrossesPlan(T * *last_slam_position_, T * pose_slam.position, index_->plan(),
                        options_.path_check_margin_m))
      ++crossings_;
  }
  last_slam_position_ = pose_slam.position;
  if (std::isfinite(pose_slam.heading)) last_slam_heading_ = pose_slam.heading;
  PlanPoseEstimate out = Project(pose_slam);
  if (has_alignment()) last_plan_position_ = out.pose.position;
  return out;
}

PlanPoseEstimate Tracker::Project(const Pose2& pose_slam) const {
  PlanPoseEstimate out;
  out.alignment_version = alignment_.version;
  out.reliability = CurrentReliability();
  // Without an alignment: slam coordinates, flagged unreliable.
  out.pose = has_alignment() ? Apply(alignment_.T_plan_slam, pose_slam) : pose_slam;
  return out;
}

std::string Tracker::FirstRegistrationDoubt(const RegistrationResult& result) const {
  if (alignment_.source == AlignmentSource::kRegistration) return {};
  if (result.ambiguity > options_.max_ambiguity) {
    char text[96];
    std::snprintf(text, sizeof text, "ambiguous: another place fits within %.0f%%",
                  100 * (1 - result.ambiguity));
    return text;
  }
  // A searched place was refined on a minute of walls and led every other place of the
  // plan; a pick may be metres off.
  const double ratio = alignment_.source == AlignmentSource::kGlobalSearch
                           ? options_.searched_first_inlier_ratio
                           : options_.first_inlier_ratio;
  if (result.points > 0 && result.inliers < ratio * result.points)
    return "too few wall points fit for a first registration";
  return {};
}

uint32_t Tracker::FirstPlaceCrossings(const Se2& T_plan_slam,
                                      const std::vector<Eigen::Vector2d>& path_slam) const {
  if (!options_.path_check || path_slam.size() < 2 || !on_pick()) return 0;
  return PathCrossings(PathOnPlan(T_plan_slam, path_slam), index_->plan(),
                       options_.path_check_margin_m);
}

bool Tracker::FirstPlaceClear(const RegistrationResult& result) const {
  // Refinement may carry the best place a little beyond the search window.
  constexpr double kMargin = 1.25;
  return result.ambiguity <= options_.clear_ambiguity &&
         Within(result.T_plan_slam, alignment_.T_plan_slam, kMargin * options_.pick_search_m,
                kMargin * options_.pick_search_rad, start_pivot_);
}

bool Tracker::Within(const Se2& T, const Se2& other, double m, double rad,
                     const std::optional<Eigen::Vector2d>& at) const {
  const Eigen::Vector3d apart = Difference(T, other, at.value_or(filter_.pivot()));
  return apart.tail<2>().norm() <= m && std::abs(apart(0)) <= rad;
}

bool Tracker::Agrees(const Se2& T, const std::optional<Se2>& earlier) const {
  return earlier && Within(T, *earlier, options_.confirm_m, options_.confirm_rad);
}

bool Tracker::PlaceConfirmed(const RegistrationResult& result, double walk_m) {
  if (!Agrees(result.T_plan_slam, pending_place_)) {
    pending_place_ = result.T_plan_slam;
    place_walk_m_ = 0;
    return false;
  }
  return place_walk_m_ >= walk_m;
}

bool Tracker::ExplainsWallsInstead(const RegistrationResult& result,
                                   const std::vector<Eigen::Vector2d>& cloud, double new_score,
                                   double old_score) const {
  if (options_.jump_clear_ratio <= 0 || cloud.empty() ||
      !(new_score <= options_.jump_clear_ratio * old_score))
    return false;
  const double need = options_.jump_clear_inliers * static_cast<double>(cloud.size());
  const IcpOptions& o = options_.icp;
  RegistrationResult fits, in_use;
  EvaluateFit(cloud, *index_, result.T_plan_slam, o.max_correspondence_m, o.inlier_threshold_m,
              &fits, nullptr);
  EvaluateFit(cloud, *index_, alignment_.T_plan_slam, o.max_correspondence_m, o.inlier_threshold_m,
              &in_use, nullptr);
  return fits.inliers >= need && in_use.inliers < need;
}

uint32_t Tracker::MinPoints() const {
  // A pick, flip or place found by searching is checked against the walls as soon as a
  // few are in: a wrong one is flagged in seconds (and the walls' directions turn it).
  return alignment_.source == AlignmentSource::kRegistration
             ? options_.min_points
             : std::min(options_.min_points, options_.check_min_points);
}

bool Tracker::RegistrationDue(int64_t now_ns, size_t live_points, size_t new_points) const {
  if (!index_ || !has_alignment() || live_points < MinPoints() || new_points == 0) return false;
  if (new_points >= options_.min_new_points) return true;
  if (options_.min_walk_m > 0 && walked_since_start_m_ >= options_.min_walk_m) return true;
  return static_cast<double>(now_ns - last_start_ns_) * 1e-9 >= options_.max_interval_s;
}

Tracker::Decision Tracker::Offer(const RegistrationResult& result,
                                 const std::vector<Eigen::Vector2d>& cloud,
                                 uint64_t based_on_version, int64_t stamp_ns,
                                 const std::vector<Eigen::Vector2d>& path_slam) {
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
  double old_score = 0, new_score = 0;
  EvaluateFit(cloud, *index_, alignment_.T_plan_slam, cap, o.inlier_threshold_m, nullptr,
              &old_score);
  const bool finite = result.T_plan_slam.t.allFinite() && std::isfinite(result.T_plan_slam.theta);
  if (finite) {
    EvaluateFit(cloud, *index_, result.T_plan_slam, cap, o.inlier_threshold_m, nullptr, &new_score);
  }
  PredictToWearer();
  if (!finite) {
    d.reason = "non-finite result";
  } else if (result.matched < 3) {
    d.reason = "registration failed: " + result.reason;
  } else if (new_score > old_score * options_.worse_fit_ratio) {
    d.reason = "fit worse than the alignment in use";
  } else if (alignment_.source != AlignmentSource::kRegistration &&
             cloud.size() < options_.min_points) {
    // check_min_points: enough to tell a pick that fits no walls near it, not to place.
    d.reason = "a check on few walls: a place waits for more";
  } else if (const uint32_t crossings = FirstPlaceCrossings(result.T_plan_slam, path_slam);
             crossings > 0) {
    // A wrong pick's walls often fit a corner or a wall nearby as well as the true one
    // (a hall's few walls fit anywhere); the walk so far tells them apart. The pick is
    // then in doubt too: flagged as a walk through a wall until an alignment under which
    // the walk goes through none (a right pick's first place never walked through one
    // in the suites, a wrong one's often does).
    d.reason = "first place: the walk so far would cross " + std::to_string(crossings) + " wall" +
               (crossings == 1 ? "" : "s") + " of the plan there";
    crossings_ = std::max(crossings_, crossings);
  } else if (const std::string doubt = FirstRegistrationDoubt(result);
             alignment_.source != AlignmentSource::kRegistration &&
             !(doubt.empty() && FirstPlaceClear(result)) &&
             !PlaceConfirmed(result, doubt.empty() ? 0.0 : options_.confirm_walk_m)) {
    // The first place after a pick is taken when the next result lands on it too, or,
    // when in doubt, the results over confirm_walk_m.
    d.reason = doubt.empty() ? "first place: waits for the next result to agree" : doubt;
  } else {
    // The measurement: the result, with the information its wall points give about the
    // wearer (none along a corridor's axis).
    size_t inliers = 0;
    const Eigen::Matrix3d H = FitInformation(cloud, *index_, result.T_plan_slam, filter_.pivot(),
                                             o.inlier_threshold_m, &inliers);
    const Eigen::Matrix3d R = filter_.MeasurementCovariance(H, inliers);
    if (inliers > 0) {
      const Eigen::Matrix2d mean_t = H.block<2, 2>(1, 1) / static_cast<double>(inliers);
      const double lo = std::max(1e-6, mean_t.selfadjointView<Eigen::Lower>().eigenvalues()(0));
      weakest_direction_ = options_.filter.measurement_sigma_m / std::sqrt(lo);
    }
    const AlignmentFilter::Update u = filter_.Fuse(result.T_plan_slam, R);
    last_disagreement_ = std::sqrt(u.mahalanobis2);
    if (!u.gated) {
      d.accepted = true;
    } else {
      // Beyond the gate: a wrong minimum, or the alignment in use is wrong. Taken only
      // when registrations keep landing on it while the wearer walks on (snapshots a few
      // seconds apart share most of their points, so one more agreeing result proves
      // little), and when it fits clearly better than the alignment in use; or at once
      // when the walls fit it and not the alignment in use (jump_clear_ratio).
      const bool agrees = Agrees(result.T_plan_slam, pending_jump_);
      if (!agrees) pending_walk_m_ = 0;
      const bool confirmed = agrees && pending_walk_m_ >= options_.confirm_walk_m &&
                             new_score < options_.jump_score_ratio * old_score;
      if (confirmed || ExplainsWallsInstead(result, cloud, new_score, old_score)) {
        filter_.Reset(result.T_plan_slam, R + filter_.P(), filter_.pivot());
        d.accepted = true;
        d.reason =
            confirmed ? "jump confirmed" : "jump: the walls fit it, not the alignment in use";
      } else {
        pending_jump_ = result.T_plan_slam;
        char text[128];
        std::snprintf(text, sizeof text,
                      "disagrees with the alignment in use (%.2f m, %.1f deg, %.1f sigma): "
                      "waits for confirmation",
                      u.innovation.tail<2>().norm(), std::abs(u.innovation(0)) * 180 / M_PI,
                      last_disagreement_);
        d.reason = text;
      }
    }
  }
  if (d.accepted) {
    // A registration refits the walls, not the walk: after a step through a wall, the
    // flag stays while the walk of the window goes through a wall under the new
    // alignment too (a wrong place refined is the same wrong place).
    const uint32_t still = crossings_ > 0 && options_.path_check && path_slam.size() >= 2
                               ? PathCrossings(PathOnPlan(filter_.T(), path_slam), index_->plan(),
                                               options_.path_check_margin_m)
                               : 0;
    SetAlignment(filter_.T(), AlignmentSource::kRegistration, stamp_ns);
    crossings_ = still;
    alignment_.registration = result;
    alignment_.registration->T_plan_slam = filter_.T();
    ++fused_;
    walked_since_fused_m_ = 0;
    history_.push_back(alignment_);
    if (history_.size() > options_.history) history_.erase(history_.begin());
  }
  RegistrationResult fit;
  EvaluateFit(cloud, *index_, alignment_.T_plan_slam, o.max_correspondence_m, o.inlier_threshold_m,
              &fit, nullptr);
  fit.method = d.accepted ? result.method : "current";
  current_fit_ = fit;
  return d;
}

std::optional<double> Tracker::TurnToWalls(double omega_rad, uint64_t based_on_version,
                                           int64_t stamp_ns) {
  if (!has_alignment() || alignment_.source == AlignmentSource::kRegistration ||
      based_on_version != alignment_.version || !std::isfinite(omega_rad))
    return std::nullopt;
  // A heading measurement of turn_sigma_rad against the heading the filter has: beyond
  // 3 sigma it is another peak of the histogram (clutter, a wing at another angle), not
  // a correction; within, weighted as a Kalman update.
  const double var = FilterAtWearer().P()(0, 0);
  const double meas = options_.turn_sigma_rad * options_.turn_sigma_rad;
  if (omega_rad * omega_rad > 9.0 * (var + meas)) return std::nullopt;
  const double k = var / (var + meas);
  const double omega = k * omega_rad;
  pending_jump_.reset();
  alignment_.T_plan_slam =
      Perturb(alignment_.T_plan_slam, Eigen::Vector3d(omega, 0, 0), start_pivot_);
  alignment_.version = next_version_++;
  alignment_.stamp_ns = stamp_ns;
  // The heading narrowed, but never below one measurement's: the next one sees mostly
  // the same walls.
  StartFilterAtPick(std::max((1 - k) * var, meas));
  walked_since_predict_m_ = turned_since_predict_rad_ = 0;
  return omega;
}

const char* ReliabilityFeatures::Name(int i) {
  static const char* const kNames[ReliabilityModel::kFeatures] = {
      "inlier_ratio",      "inlier_rmse_m", "position_sigma_m", "heading_sigma_deg",
      "weakest_direction", "disagreement",  "log_accepted",     "log_walked_m"};
  return i >= 0 && i < ReliabilityModel::kFeatures ? kNames[i] : "?";
}

ReliabilityFeatures Tracker::CurrentFeatures() const {
  ReliabilityFeatures f;
  if (current_fit_ && current_fit_->points) {
    f.inlier_ratio = static_cast<double>(current_fit_->inliers) / current_fit_->points;
    f.inlier_rmse_m = current_fit_->inlier_rmse;
  }
  const AlignmentFilter at_wearer = FilterAtWearer();
  f.position_sigma_m = at_wearer.position_sigma_m();
  f.heading_sigma_deg = at_wearer.heading_sigma_rad() * 180 / M_PI;
  f.weakest_direction = std::min(weakest_direction_, 10.0);
  f.disagreement = std::min(last_disagreement_, 10.0);
  f.accepted = std::log1p(fused_);
  f.walked_m = std::log1p(walked_since_fused_m_);
  return f;
}

double ReliabilityModel::Probability(const std::array<double, kFeatures>& x) const {
  double z = bias;
  for (int i = 0; i < kFeatures; ++i) z += weights[i] * x[i];
  return 1.0 / (1.0 + std::exp(-z));
}

Reliability Tracker::Assess(const ReliabilityFeatures& f) const {
  const ReliabilityModel& m = options_.reliability;
  const auto x = f.Vector();
  // The reason is the feature that lowers the probability most against a typical good
  // fix (the values below).
  static constexpr std::array<double, ReliabilityModel::kFeatures> kGood = {0.95, 0.06, 0.15, 0.5,
                                                                            0.3,  1.0,  3.0,  1.0};
  int worst = -1;
  double worst_drop = 0;
  for (int i = 0; i < ReliabilityModel::kFeatures; ++i) {
    const double drop = m.weights[i] * (x[i] - kGood[i]);
    if (drop < worst_drop) {
      worst_drop = drop;
      worst = i;
    }
  }
  Reliability r;
  r.probability = m.Probability(x);
  r.rmse_m = f.inlier_rmse_m;
  r.flag = r.probability >= m.reliable_probability   ? ReliabilityFlag::kReliable
           : r.probability >= m.degraded_probability ? ReliabilityFlag::kDegraded
                                                     : ReliabilityFlag::kUnreliable;
  char text[96];
  switch (worst) {
    case 0:
      std::snprintf(text, sizeof text, "%.0f%% of wall points match the plan",
                    100 * f.inlier_ratio);
      break;
    case 1:
      std::snprintf(text, sizeof text, "walls fit loosely (%.2f m RMSE)", f.inlier_rmse_m);
      break;
    case 2:
      std::snprintf(text, sizeof text, "position uncertain (%.2f m)", f.position_sigma_m);
      break;
    case 3:
      std::snprintf(text, sizeof text, "heading uncertain (%.1f deg)", f.heading_sigma_deg);
      break;
    case 4:
      std::snprintf(text, sizeof text, "walls constrain one direction only (corridor)");
      break;
    case 5:
      std::snprintf(text, sizeof text, "the latest registration disagreed (%.1f sigma)",
                    f.disagreement);
      break;
    case 6: std::snprintf(text, sizeof text, "few registrations since the pick"); break;
    case 7:
      std::snprintf(text, sizeof text, "%.0f m walked since the latest registration",
                    std::expm1(f.walked_m));
      break;
    default: std::snprintf(text, sizeof text, "registered"); break;
  }
  r.reason = r.flag == ReliabilityFlag::kReliable ? "registered" : text;
  return r;
}

Reliability Tracker::CurrentReliability() const {
  Reliability r;
  if (!index_) {
    r.reason = "no floor plan";
    return r;
  }
  if (!has_alignment()) {
    r.reason = options_.global_search ? "no alignment: searching the plan"
                                      : "no alignment: waiting for a wall pick";
    return r;
  }
  r = Assess(CurrentFeatures());
  if (crossings_ > 0) {
    // The wearer walked through a wall of the plan under this alignment.
    r.flag = ReliabilityFlag::kUnreliable;
    r.reason = "the path crosses a wall of the plan";
    return r;
  }
  if (const double off = OffPlanM(); off > 0) {
    char text[64];
    std::snprintf(text, sizeof text, "outside the floor plan (%.1f m)",
                  off + options_.off_plan_margin_m);
    r.flag = ReliabilityFlag::kUnreliable;
    r.reason = text;
    return r;
  }
  if (options_.global_search && WallsDoNotFit()) {
    // The alignment in use stops explaining the walls (a wrong pick, a wrong place): the
    // search is checking the plan for a better one.
    char text[96];
    std::snprintf(text, sizeof text, "the walls do not fit the alignment (%u of %u)",
                  current_fit_->inliers, current_fit_->points);
    r.flag = ReliabilityFlag::kUnreliable;
    r.reason = text;
    return r;
  }
  if (on_pick() && r.flag == ReliabilityFlag::kReliable) {
    // Checked on a few walls (check_min_points), not registered yet: a wrong pick's few
    // walls often fit it as well as a right pick's; only a registration places.
    r.flag = ReliabilityFlag::kDegraded;
    r.reason = alignment_.source == AlignmentSource::kFlip ? "flipped, not yet registered"
                                                           : "wall pick, not yet registered";
  }
  if (!placement_confirmed_ && r.flag == ReliabilityFlag::kReliable) {
    r.flag = ReliabilityFlag::kDegraded;
    r.reason = "placed by searching the plan, not yet confirmed";
  }
  if (!current_fit_) {
    // Not yet checked against the walls (a pick, a restart, another floor): DEGRADED,
    // whatever the odds.
    r.flag = ReliabilityFlag::kDegraded;
    r.reason = restored_                                     ? "restored, not yet checked"
               : floor_changed_                              ? "floor changed, not yet checked"
               : alignment_.source == AlignmentSource::kFlip ? "flipped, not yet checked"
               : alignment_.source == AlignmentSource::kGlobalSearch
                   ? "placed by searching the plan, not yet checked"
                   : "wall pick, not yet checked";
  }
  return r;
}

TrackState StateOf(bool has_plan, bool has_alignment, ReliabilityFlag flag) {
  if (!has_plan) return TrackState::kWaitingForPlan;
  if (!has_alignment) return TrackState::kWaitingForAlignment;
  switch (flag) {
    case ReliabilityFlag::kReliable: return TrackState::kTracking;
    case ReliabilityFlag::kDegraded: return TrackState::kDegraded;
    case ReliabilityFlag::kUnreliable: return TrackState::kLost;
  }
  return TrackState::kLost;
}

TrackState Tracker::state() const {
  return StateOf(has_plan(), has_alignment(), CurrentReliability().flag);
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
