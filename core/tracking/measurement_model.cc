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

namespace {

// PointLogLikelihood below ClutterOnlyFromM (and reach), tabulated at kSteps + 1 distances
// and interpolated linearly: an exp and a log a point were an eighth of a laser log's CPU.
// The curve bends at most 5 / sigma^2 (where the hit density gives way to clutter), so the
// interpolation is within 5 / sigma^2 * step^2 / 8 of it: 3e-6 at any sigma, as the step
// is about 9 sigma / kSteps; the distance grid's millimetres move it a hundred times more.
class PointLogLikelihoodTable {
 public:
  static constexpr int kSteps = 4096;

  // For this model and reach, building it when it was for another (or none).
  void Use(const MeasurementModel& m, double reach_m) {
    if (m.sigma_m == sigma_m_ && m.clutter == clutter_ && reach_m == reach_m_) return;
    sigma_m_ = m.sigma_m;
    clutter_ = m.clutter;
    reach_m_ = reach_m;
    until_m_ = std::min(m.ClutterOnlyFromM(reach_m), reach_m);
    values_.clear();
    if (!(until_m_ > 0) || !std::isfinite(until_m_)) return;
    values_.resize(kSteps + 1);
    for (int i = 0; i <= kSteps; ++i) {
      values_[i] = m.PointLogLikelihood(until_m_ * i / kSteps, reach_m);
      if (!std::isfinite(values_[i])) {
        values_.clear();
        return;
      }
    }
    per_step_ = kSteps / until_m_;
  }
  // The distances it answers: [0, until_m()), none when it could not be built.
  double until_m() const { return values_.empty() ? 0.0 : until_m_; }
  double At(double d) const {
    const double x = d * per_step_;
    const int i = std::min(static_cast<int>(x), kSteps - 1);
    return values_[i] + (x - i) * (values_[i + 1] - values_[i]);
  }

 private:
  double sigma_m_ = std::numeric_limits<double>::quiet_NaN(), clutter_ = 0, reach_m_ = 0;
  double until_m_ = 0, per_step_ = 0;
  std::vector<double> values_;
};

}  // namespace

double MeasurementModel::MeanLogLikelihood(const std::vector<Eigen::Vector2d>& points_slam,
                                           const Se2& T, const ClosestWallIndex& index,
                                           double reach_m) const {
  if (points_slam.empty()) return 0.0;
  thread_local PointLogLikelihoodTable table;  // the worker's, built once for the config
  table.Use(*this, reach_m);
  const double until_m = table.until_m();
  const Eigen::Matrix2d R = T.R();
  const double far = PointLogLikelihood(2 * reach_m, reach_m);
  const double clutter_only_m = ClutterOnlyFromM(reach_m);
  double sum = 0;
  for (const Eigen::Vector2d& p : points_slam) {
    const double d = index.Distance(R * p + T.t, clutter_only_m);
    sum += d < until_m ? table.At(d) : d <= reach_m ? PointLogLikelihood(d, reach_m) : far;
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
