#include "core/tracking/motion_model.h"

#include <cmath>

namespace floorpose::tracking {

Eigen::Vector2d MotionModel::Sigmas(double metres, double turned_rad) const {
  const double m = std::max(0.0, metres);
  const double heading =
      std::hypot(heading_rad_per_sqrt_m * std::sqrt(m), heading_per_turn * std::abs(turned_rad));
  return {heading, position_m_per_sqrt_m * std::sqrt(m)};
}

Se2 MotionModel::Sample(const Se2& T, const Eigen::Vector2d& pivot, const Eigen::Vector2d& sigmas,
                        SplitMix64& rng) const {
  const Eigen::Vector3d delta(sigmas(0) * rng.Gaussian(), sigmas(1) * rng.Gaussian(),
                              sigmas(1) * rng.Gaussian());
  return Perturb(T, delta, pivot);
}

double MotionModel::PathLogPrior(const std::vector<Eigen::Vector2d>& path_slam, const Se2& T,
                                 const ClosestWallIndex& index) const {
  int crossings = 0;
  for (size_t i = 1; i < path_slam.size(); ++i)
    crossings += index.StepCrossesWall(T * path_slam[i - 1], T * path_slam[i]);
  return crossings * std::log(through_wall);
}

}  // namespace floorpose::tracking
