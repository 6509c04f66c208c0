#include "core/alignment_filter.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

namespace floorpose {
namespace {

// d/dphi of R(phi) v at phi = 0.
Eigen::Vector2d Perp(const Eigen::Vector2d& v) { return {-v.y(), v.x()}; }

}  // namespace

Eigen::Matrix3d FitInformation(const std::vector<Eigen::Vector2d>& points,
                               const ClosestWallIndex& index, const Se2& T,
                               const Eigen::Vector2d& pivot, double inlier_threshold_m,
                               size_t* inliers) {
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  size_t n = 0;
  const Eigen::Matrix2d R = T.R();
  for (const Eigen::Vector2d& p : points) {
    const Eigen::Vector2d q = R * p + T.t;
    const auto hit = index.Query(q);
    if (!hit || hit->distance > inlier_threshold_m) continue;
    const Eigen::Vector3d J(hit->normal.dot(Perp(q - pivot)), hit->normal.x(), hit->normal.y());
    H.noalias() += J * J.transpose();
    ++n;
  }
  if (inliers) *inliers = n;
  return H;
}

Eigen::Vector3d Difference(const Se2& to, const Se2& from, const Eigen::Vector2d& pivot) {
  const Eigen::Vector2d q = from.Inverse() * pivot;  // slam point at the pivot
  const Eigen::Vector2d u = to * q - pivot;
  return {WrapAngle(to.theta - from.theta), u.x(), u.y()};
}

Se2 Perturb(const Se2& T, const Eigen::Vector3d& delta, const Eigen::Vector2d& pivot) {
  Se2 E;
  E.theta = delta(0);
  E.t = pivot + delta.tail<2>() - E.R() * pivot;
  return E * T;
}

void AlignmentFilter::Reset(const Se2& T, const Eigen::Matrix3d& P, const Eigen::Vector2d& pivot) {
  T_ = T;
  P_ = P;
  pivot_ = pivot;
  net_turn_rad_ = peak_turn_rad_ = 0.0;
  drift_since_fused_.setZero();
}

void AlignmentFilter::Predict(const Eigen::Vector2d& pivot, double metres, double turned_rad) {
  // The same perturbation about the new pivot: u' = u + phi Perp(pivot' - pivot).
  Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
  A.block<2, 1>(1, 0) = Perp(pivot - pivot_);
  P_ = A * P_ * A.transpose();
  drift_since_fused_ = A * drift_since_fused_ * A.transpose();
  pivot_ = pivot;
  const double m = std::max(0.0, metres);
  Eigen::Vector3d q(options_.heading_var_per_m * m, options_.position_var_per_m * m,
                    options_.position_var_per_m * m);
  // The yaw scale error is a bias: turning back undoes it (a head scanning left and right
  // adds nothing), so the variance follows the largest net turn so far, squared.
  if (std::isfinite(turned_rad)) {
    net_turn_rad_ += turned_rad;
    const double peak = std::max(peak_turn_rad_, std::abs(net_turn_rad_));
    const double s = options_.yaw_scale_sigma;
    q(0) += s * s * (peak * peak - peak_turn_rad_ * peak_turn_rad_);
    peak_turn_rad_ = peak;
  }
  P_ += drift_scale_ * q.asDiagonal().toDenseMatrix();
  drift_since_fused_ += q.asDiagonal().toDenseMatrix();
}

double AlignmentFilter::AskedScale(const Eigen::Vector3d& innovation,
                                   const Eigen::Matrix3d& R) const {
  // Mahalanobis distance squared of the innovation had the drift since the last fused
  // measurement been s times the prior's; decreasing in s. Solved for the median of
  // chi^2 (3 dof) by bisection on log s.
  constexpr double kMedianChi2Dof3 = 2.366;
  const Eigen::Matrix3d rest = P_ - drift_scale_ * drift_since_fused_ + R;
  auto d2 = [&](double s) {
    return innovation.dot((rest + s * drift_since_fused_).inverse() * innovation);
  };
  const double hi = options_.max_drift_scale;
  if (!(d2(0.0) > kMedianChi2Dof3)) return 0.0;
  if (!(d2(hi) < kMedianChi2Dof3)) return hi;
  double lo_s = 1e-3, hi_s = hi;
  for (int i = 0; i < 40; ++i) {
    const double mid = std::sqrt(lo_s * hi_s);
    (d2(mid) > kMedianChi2Dof3 ? lo_s : hi_s) = mid;
  }
  return std::sqrt(lo_s * hi_s);
}

Eigen::Matrix3d AlignmentFilter::MeasurementCovariance(const Eigen::Matrix3d& information,
                                                       size_t inliers) const {
  if (inliers == 0) return Eigen::Matrix3d::Identity() * 1e6;
  const double n = static_cast<double>(inliers);
  // Mean information per point, regularised so that an unconstrained direction gets a
  // large but finite variance (10^4 sigma^2 / points_equivalent).
  const Eigen::Matrix3d mean = information / n + Eigen::Matrix3d::Identity() * 1e-4;
  const double s = options_.measurement_sigma_m;
  const double k = std::min(options_.measurement_points, n);
  return mean.inverse() * (s * s / k);
}

AlignmentFilter::Update AlignmentFilter::Fuse(const Se2& measured, const Eigen::Matrix3d& R) {
  Update u;
  u.innovation = Difference(measured, T_, pivot_);
  if (!u.innovation.allFinite() || !R.allFinite()) {
    u.gated = true;
    u.mahalanobis2 = std::numeric_limits<double>::infinity();
    return u;
  }
  // Only innovations over enough drift tell its rate: right after a fused measurement
  // the heading innovation is the registration's own noise, whatever R claims.
  const Eigen::Matrix3d drift = drift_scale_ * drift_since_fused_;
  if (options_.drift_window > 0 &&
      (drift(0, 0) >= R(0, 0) || drift(1, 1) + drift(2, 2) >= R(1, 1) + R(2, 2))) {
    u.drift_scale = AskedScale(u.innovation, R);
    asked_scales_.push_back(u.drift_scale);
    if (asked_scales_.size() > static_cast<size_t>(options_.drift_window))
      asked_scales_.pop_front();
    std::vector<double> sorted(asked_scales_.begin(), asked_scales_.end());
    const size_t q = sorted.size() / 2;
    std::nth_element(sorted.begin(), sorted.begin() + q, sorted.end());
    const double scale = std::clamp(sorted[q], 1.0, options_.max_drift_scale);
    // The drift since the last fused measurement at the new scale, this innovation
    // included.
    P_ += (scale - drift_scale_) * drift_since_fused_;
    drift_scale_ = scale;
  }
  const Eigen::Matrix3d S_inv = (P_ + R).inverse();
  u.mahalanobis2 = u.innovation.dot(S_inv * u.innovation);
  if (!std::isfinite(u.mahalanobis2) || u.mahalanobis2 > options_.gate_chi2) {
    u.gated = true;
    return u;
  }
  const Eigen::Matrix3d K = P_ * S_inv;
  u.correction = K * u.innovation;
  T_ = Perturb(T_, u.correction, pivot_);
  // Joseph form keeps P symmetric and positive.
  const Eigen::Matrix3d I_K = Eigen::Matrix3d::Identity() - K;
  P_ = I_K * P_ * I_K.transpose() + K * R * K.transpose();
  P_ = 0.5 * (P_ + P_.transpose()).eval();
  net_turn_rad_ = peak_turn_rad_ = 0.0;
  drift_since_fused_.setZero();
  return u;
}

double AlignmentFilter::position_sigma_m() const {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(P_.block<2, 2>(1, 1));
  return std::sqrt(std::max(0.0, es.eigenvalues()(1)));
}

double AlignmentFilter::heading_sigma_rad() const { return std::sqrt(std::max(0.0, P_(0, 0))); }

}  // namespace floorpose
