// The alignment T_plan_slam as an estimate with an uncertainty that grows as the wearer
// walks (the SLAM drifts) and shrinks with every registration that agrees with it: a
// Kalman filter on SE(2), the way a GNSS/INS filter treats fixes. Each registration
// only sees the last few seconds of walls; the filter carries what the older ones said,
// keeps the corridor's unconstrained axis where the prior put it, and gates results that
// disagree with everything before (a wrong local minimum, a wall that is not on the plan).
//
// Perturbations are taken about a pivot on the plan, normally the wearer:
//   delta = (phi, u):  x -> R(phi) (x - pivot) + pivot + u
// so that the covariance says directly how far off the wearer is (u) and how far their
// heading is (phi), without the lever arm of the plan's origin.
#pragma once

#include <Eigen/Core>
#include <deque>
#include <vector>

#include "core/closest_wall_index.h"
#include "core/se2.h"

namespace floorpose {

struct AlignmentFilterOptions {
  // Drift of the SLAM frame per metre walked, as variance growth (random walk):
  // heading rad^2/m and position m^2/m at the wearer.
  double heading_var_per_m = (0.3 * M_PI / 180) * (0.3 * M_PI / 180);  // 3 deg after 100 m
  double position_var_per_m = 0.06 * 0.06;                             // 0.6 m after 100 m
  // The SLAM's error in measuring its own turning, a fraction: its heading drifts by this
  // times the net turn, so that a wearer circling a hall with no wall in range drifts
  // degrees without walking far. Heading variance (this x the largest net turn since the
  // last fused registration)^2.
  double yaw_scale_sigma = 0.005;
  // A registration's covariance: sigma^2 / points_equivalent times the inverse of the
  // mean information of its wall points (so a corridor's axis gets no information).
  // The points of one snapshot share the drift and the plan's errors: they are worth a
  // handful of independent measurements, not hundreds.
  double measurement_sigma_m = 0.1;
  double measurement_points = 8.0;
  // Innovations beyond this Mahalanobis distance squared (chi^2, 3 dof) are outliers.
  double gate_chi2 = 16.3;  // 99.9%
  // The heading drift above is a prior, not a fact: a wheel's odometry or a poor SLAM
  // can drift ten times faster. Once the drift since the last fused registration rises
  // above the registration's own noise, each registration tells the scale of the drift
  // since then that would have made its innovation typical (the median of chi^2, 3 dof);
  // the median of the last drift_window of those, at least 1 and at most
  // max_drift_scale, multiplies the whole drift (adaptive noise estimation, Mehra 1970).
  // A median, so a few wrong places in a row do not widen the gate; but a registration
  // sliding along a corridor whose walls are not all on the plan asks for more drift
  // result after result, so it is off by default (docs/evaluation.md); 0 turns it off.
  int drift_window = 0;
  double max_drift_scale = 400.0;
};

// The information (sum of J^T J over the points within inlier_threshold_m of a wall under
// T_plan_slam) of a cloud about `pivot`, unknowns (phi, ux, uy) as above; *inliers counts
// those points.
Eigen::Matrix3d FitInformation(const std::vector<Eigen::Vector2d>& points_slam,
                               const ClosestWallIndex& index, const Se2& T_plan_slam,
                               const Eigen::Vector2d& pivot, double inlier_threshold_m,
                               size_t* inliers);

// The perturbation (phi, u) about `pivot` that takes `from` to `to`: to = Exp(delta) from.
Eigen::Vector3d Difference(const Se2& to, const Se2& from, const Eigen::Vector2d& pivot);
// Exp(delta) * T.
Se2 Perturb(const Se2& T, const Eigen::Vector3d& delta, const Eigen::Vector2d& pivot);

class AlignmentFilter {
 public:
  explicit AlignmentFilter(AlignmentFilterOptions options = {}) : options_(options) {}

  // Starts over at T with covariance P about pivot.
  void Reset(const Se2& T, const Eigen::Matrix3d& P, const Eigen::Vector2d& pivot);

  // The wearer walked `metres`, turned by `turned_rad` (signed, slam) and is now at
  // `pivot` (plan): moves the covariance there and adds the drift of the walk.
  void Predict(const Eigen::Vector2d& pivot, double metres, double turned_rad = 0.0);

  // The covariance of a measurement from a registration: R about the current pivot.
  Eigen::Matrix3d MeasurementCovariance(const Eigen::Matrix3d& information, size_t inliers) const;

  struct Update {
    Eigen::Vector3d innovation = Eigen::Vector3d::Zero();  // measured minus predicted
    double mahalanobis2 = 0;
    bool gated = false;                                    // beyond gate_chi2: not applied
    Eigen::Vector3d correction = Eigen::Vector3d::Zero();  // what was applied
    double drift_scale = 1;  // the drift this innovation asked for, times the prior's
  };
  // Fuses a measured alignment with covariance R (about the current pivot).
  Update Fuse(const Se2& measured, const Eigen::Matrix3d& R);

  const Se2& T() const { return T_; }
  const Eigen::Matrix3d& P() const { return P_; }
  const Eigen::Vector2d& pivot() const { return pivot_; }
  // One-sigma position and heading uncertainty at the pivot (largest axis), m and rad.
  double position_sigma_m() const;
  double heading_sigma_rad() const;
  // What the drift prior is multiplied by now (1 until innovations say otherwise), and
  // setting it again after a restart.
  double drift_scale() const { return drift_scale_; }
  void set_drift_scale(double scale) { drift_scale_ = scale; }
  const AlignmentFilterOptions& options() const { return options_; }
  // Other options from now on, keeping the estimate (Tracker::SetOdometryOptions).
  void set_options(const AlignmentFilterOptions& options) { options_ = options; }

 private:
  // The heading drift scale that makes this innovation typical (see drift_window).
  double AskedScale(const Eigen::Vector3d& innovation, const Eigen::Matrix3d& R) const;

  AlignmentFilterOptions options_;
  Se2 T_;
  Eigen::Matrix3d P_ = Eigen::Matrix3d::Identity();
  Eigen::Vector2d pivot_ = Eigen::Vector2d::Zero();
  double net_turn_rad_ = 0.0;   // since Reset or the last fused measurement...
  double peak_turn_rad_ = 0.0;  // ...and its largest magnitude
  // The heading drift added since the last fused measurement at the prior's scale (moved
  // with the pivot like P), and the drift scales the latest innovations asked for.
  Eigen::Matrix3d drift_since_fused_ = Eigen::Matrix3d::Zero();
  std::deque<double> asked_scales_;
  double drift_scale_ = 1.0;
};

}  // namespace floorpose
