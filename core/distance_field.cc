#include "core/distance_field.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/closest_wall_index.h"

namespace floorpose {

DistanceField::DistanceField(const ClosestWallIndex& index, double cell_m) {
  const FloorPlan& plan = index.plan();
  reach_m_ = index.max_distance_m();
  if (!(cell_m > 0) || plan.segments.empty() || !(reach_m_ > 0)) return;
  // Beyond the reach of every wall the field holds the reach: one more node each side.
  const Eigen::Vector2d margin = Eigen::Vector2d::Constant(reach_m_ + cell_m);
  const Eigen::Vector2d extent = plan.max - plan.min + 2 * margin;
  // A stray far-away segment must not make gigabytes: the index's own cap on cells.
  constexpr double kMaxNodes = 1 << 25;  // 64 MB
  while (std::ceil(extent.x() / cell_m + 2) * std::ceil(extent.y() / cell_m + 2) > kMaxNodes)
    cell_m *= 2;
  cell_m_ = cell_m;
  inv_cell_ = 1.0 / cell_m;
  step_m_ = reach_m_ / std::numeric_limits<uint16_t>::max();
  origin_ = plan.min - margin;
  nx_ = static_cast<int>(std::ceil(extent.x() / cell_m)) + 2;
  ny_ = static_cast<int>(std::ceil(extent.y() / cell_m)) + 2;
  values_.resize(static_cast<size_t>(nx_) * static_cast<size_t>(ny_));
  for (int iy = 0; iy < ny_; ++iy) {
    for (int ix = 0; ix < nx_; ++ix) {
      const auto hit = index.Query(origin_ + cell_m * Eigen::Vector2d(ix, iy));
      const double d = hit ? std::min(hit->distance, reach_m_) : reach_m_;
      values_[static_cast<size_t>(iy) * nx_ + ix] = static_cast<uint16_t>(std::lround(d / step_m_));
    }
  }
}

}  // namespace floorpose
