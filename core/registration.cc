#include "core/registration.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace floorpose {

void EvaluateFit(const std::vector<Eigen::Vector2d>& points, const ClosestWallIndex& index,
                 const Se2& T, double max_corr, double inlier_threshold,
                 RegistrationResult* result, double* truncated_mse) {
  const Eigen::Matrix2d R = T.R();
  double sum_matched = 0, sum_inlier = 0, sum_trunc = 0;
  uint32_t matched = 0, inliers = 0;
  const double cap2 = max_corr * max_corr;
  for (const Eigen::Vector2d& p : points) {
    const auto hit = index.Query(R * p + T.t);
    if (!hit || hit->distance > max_corr) {
      sum_trunc += cap2;
      continue;
    }
    const double d2 = hit->distance * hit->distance;
    sum_trunc += d2;
    sum_matched += d2;
    ++matched;
    if (hit->distance <= inlier_threshold) {
      sum_inlier += d2;
      ++inliers;
    }
  }
  if (result) {
    result->points = static_cast<uint32_t>(points.size());
    result->matched = matched;
    result->inliers = inliers;
    result->rmse = matched ? std::sqrt(sum_matched / matched) : 0.0;
    result->inlier_rmse = inliers ? std::sqrt(sum_inlier / inliers) : 0.0;
  }
  if (truncated_mse) *truncated_mse = points.empty() ? cap2 : sum_trunc / points.size();
}

namespace {

struct Pair {
  Eigen::Vector2d p;  // transformed point
  Eigen::Vector2d n;  // wall normal
  double r;           // signed point-to-line residual n . (p - y)
  double d;           // distance to the closest point on the segment
};

}  // namespace

RegistrationResult RegisterIcp(const std::vector<Eigen::Vector2d>& points,
                               const ClosestWallIndex& index, const Se2& initial,
                               const IcpOptions& o) {
  RegistrationResult result;
  result.method = "icp";
  result.T_plan_slam = initial;
  Se2 T = initial;
  if (points.size() < 3) {
    result.reason = "fewer than 3 points";
    EvaluateFit(points, index, T, o.max_correspondence_m, o.inlier_threshold_m, &result, nullptr);
    return result;
  }
  std::vector<Pair> pairs;
  pairs.reserve(points.size());
  std::vector<double> abs_r;
  bool converged_at_finest = false;

  for (int h = static_cast<int>(o.levels); h >= 0; --h) {
    const size_t stride = size_t{1} << h;
    const uint32_t max_iter = std::max<uint32_t>(1, o.max_iterations >> h);
    bool converged = false;
    for (uint32_t it = 0; it < max_iter; ++it) {
      ++result.iterations;
      const Eigen::Matrix2d R = T.R();
      pairs.clear();
      for (size_t i = 0; i < points.size(); i += stride) {
        const Eigen::Vector2d p = R * points[i] + T.t;
        const auto hit = index.Query(p);
        if (!hit || hit->distance > o.max_correspondence_m) continue;
        pairs.push_back({p, hit->normal, hit->normal.dot(p - hit->point), hit->distance});
      }
      if (pairs.size() < 3) {
        result.reason = "fewer than 3 correspondences";
        break;
      }
      // Picky ICP (Zinsser et al. 2003): reject pairs beyond reject_sigma deviations.
      double sum2 = 0;
      for (const Pair& q : pairs) sum2 += q.d * q.d;
      const double sigma = std::sqrt(sum2 / pairs.size());
      const double reject = std::max(o.reject_sigma * sigma, 0.01);
      // Cauchy scale tied to the data: the median absolute residual of kept pairs.
      abs_r.clear();
      for (const Pair& q : pairs)
        if (q.d <= reject) abs_r.push_back(std::abs(q.r));
      if (abs_r.size() < 3) {
        result.reason = "fewer than 3 pairs after rejection";
        break;
      }
      std::nth_element(abs_r.begin(), abs_r.begin() + abs_r.size() / 2, abs_r.end());
      const double c = std::max(o.cauchy_scale_factor * abs_r[abs_r.size() / 2], 0.01);
      Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
      for (const Pair& q : pairs) centroid += q.p;
      centroid /= static_cast<double>(pairs.size());

      // Equation 4.4 in 2D about the centroid: A_i = [p x n, n], b_i = n . (p - y).
      Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      for (const Pair& q : pairs) {
        if (q.d > reject) continue;
        const Eigen::Vector2d p = q.p - centroid;
        const Eigen::Vector3d a(p.x() * q.n.y() - p.y() * q.n.x(), q.n.x(), q.n.y());
        const double w = o.cauchy_scale_factor > 0 ? 1.0 / (1.0 + (q.r / c) * (q.r / c)) : 1.0;
        H.noalias() += w * a * a.transpose();
        g.noalias() += w * a * q.r;
      }
      result.normal_matrix = H;
      const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
      if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) {
        result.reason = "singular normal matrix";
        break;
      }
      const Eigen::Vector3d delta = -ldlt.solve(g);
      if (!delta.allFinite()) {
        result.reason = "non-finite update";
        break;
      }
      // Rotate by delta(0) about the centroid, then translate.
      const Se2 step_about_centroid{delta(0), centroid + delta.tail<2>() -
                                                  Se2{delta(0), {0, 0}}.R() * centroid};
      T = step_about_centroid * T;
      if (std::abs(delta(0)) < o.converge_rotation_rad &&
          delta.tail<2>().norm() < o.converge_translation_m) {
        converged = true;
        break;
      }
    }
    if (!result.reason.empty()) break;
    converged_at_finest = converged;
  }

  result.T_plan_slam = T;
  result.converged = result.reason.empty() && converged_at_finest;
  if (result.reason.empty() && !result.converged) result.reason = "iteration limit";
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(result.normal_matrix,
                                                           Eigen::EigenvaluesOnly);
  result.eigenvalues = eig.eigenvalues();
  EvaluateFit(points, index, T, o.max_correspondence_m, o.inlier_threshold_m, &result, nullptr);
  return result;
}

}  // namespace floorpose
