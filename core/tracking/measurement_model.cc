#include "core/tracking/measurement_model.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace floorpose::tracking {

double MeasurementModel::HitDensity(double d) const {
  return std::sqrt(2.0 / M_PI) / sigma_m * std::exp(-0.5 * d * d / (sigma_m * sigma_m));
}

double MeasurementModel::PointLogLikelihood(double d, double reach_m) const {
  // The hit density mixed with a uniform one over the reach.
  const double in_reach = d <= reach_m ? 1.0 : 0.0;
  return std::log((1.0 - clutter) * HitDensity(d) * in_reach + clutter / reach_m);
}

double MeasurementModel::ClutterOnlyFromM(double reach_m) const {
  if (!(clutter > 0)) return std::numeric_limits<double>::infinity();
  // (1 - clutter) HitDensity(d) < 2^-55 clutter / reach_m, solved for d.
  const double peak = (1.0 - clutter) * HitDensity(0.0);
  const double ratio = std::log(peak * reach_m / clutter) + 55 * std::log(2.0);
  if (std::isnan(ratio)) return std::numeric_limits<double>::infinity();  // a degenerate model
  return ratio > 0 ? sigma_m * std::sqrt(2.0 * ratio) : 0.0;
}

double MeasurementModel::MeanLogLikelihood(const std::vector<Eigen::Vector2d>& points_slam,
                                           const Se2& T, const ClosestWallIndex& index,
                                           double reach_m) const {
  if (points_slam.empty()) return 0.0;
  const Eigen::Matrix2d R = T.R();
  const double far = PointLogLikelihood(2 * reach_m, reach_m);
  const double clutter_only_m = ClutterOnlyFromM(reach_m);
  double sum = 0;
  for (const Eigen::Vector2d& p : points_slam) {
    const double d = index.Distance(R * p + T.t, clutter_only_m);
    sum += d <= reach_m ? PointLogLikelihood(d, reach_m) : far;
  }
  return sum / static_cast<double>(points_slam.size());
}

std::vector<double> NearestWallPoint(const std::vector<Eigen::Vector2d>& positions,
                                     const std::vector<Eigen::Vector2d>& points) {
  std::vector<double> nearest(positions.size(), std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < positions.size(); ++i)
    for (const Eigen::Vector2d& p : points)
      nearest[i] = std::min(nearest[i], (p - positions[i]).squaredNorm());
  for (double& d : nearest) d = std::sqrt(d);
  return nearest;
}

SightFit SightLogLikelihood(const MeasurementModel& model,
                            const std::vector<Eigen::Vector2d>& positions_slam,
                            const std::vector<double>& nearest_point, const Se2& T,
                            const ClosestWallIndex& index) {
  const double missed = std::log(model.clutter), seen = std::log1p(-model.clutter);
  SightFit fit;
  for (size_t i = 0; i < positions_slam.size(); ++i) {
    const double plan = std::min(index.Distance(T * positions_slam[i]), kSightM);
    if (plan < kBodyM) continue;  // a walk through a plan line: the motion model's to price
    const double mesh = std::min(nearest_point[i], kSightM);
    fit.log_likelihood += std::abs(mesh - plan) > kSeenMarginM ? missed : seen;
    ++fit.asked;
  }
  return fit;
}

}  // namespace floorpose::tracking
