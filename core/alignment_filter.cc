#include "core/alignment_filter.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

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
}

void AlignmentFilter::Predict(const Eigen::Vector2d& pivot, double metres, double turned_rad) {
  // The same perturbation about the new pivot: u' = u + phi Perp(pivot' - pivot).
  Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
  A.block<2, 1>(1, 0) = Perp(pivot - pivot_);
  P_ = A * P_ * A.transpose();
  pivot_ = pivot;
  const double m = std::max(0.0, metres);
  P_(0, 0) += options_.heading_var_per_m * m;
  P_(1, 1) += options_.position_var_per_m * m;
  P_(2, 2) += options_.position_var_per_m * m;
  // The yaw scale error is a bias: turning back undoes it (a head scanning left and right
  // adds nothing), so the variance follows the largest net turn so far, squared.
  if (std::isfinite(turned_rad)) {
    net_turn_rad_ += turned_rad;
    const double peak = std::max(peak_turn_rad_, std::abs(net_turn_rad_));
    const double s = options_.yaw_scale_sigma;
    P_(0, 0) += s * s * (peak * peak - peak_turn_rad_ * peak_turn_rad_);
    peak_turn_rad_ = peak;
  }
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
  return u;
}

double AlignmentFilter::position_sigma_m() const {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(P_.block<2, 2>(1, 1));
  return std::sqrt(std::max(0.0, es.eigenvalues()(1)));
}

double AlignmentFilter::heading_sigma_rad() const { return std::sqrt(std::max(0.0, P_(0, 0))); }

}  // namespace floorpose
