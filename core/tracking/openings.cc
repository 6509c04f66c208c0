#include "core/tracking/openings.h"

#include <algorithm>
#include <cmath>

namespace floorpose::tracking {

uint64_t Openings::Key(int64_t ix, int64_t iy) {
  return (static_cast<uint64_t>(ix) << 32) ^ static_cast<uint32_t>(iy);
}

double Openings::Open(const Eigen::Vector2d& at) const {
  double p = through_wall_;
  if (open_.empty() || !at.allFinite()) return p;
  const int64_t ix = static_cast<int64_t>(std::floor(at.x() / kCell_m));
  const int64_t iy = static_cast<int64_t>(std::floor(at.y() / kCell_m));
  for (int64_t dx = -1; dx <= 1; ++dx)
    for (int64_t dy = -1; dy <= 1; ++dy)
      if (const auto it = open_.find(Key(ix + dx, iy + dy)); it != open_.end())
        p = std::max(p, it->second);
  return p;
}

void Openings::Observe(const Eigen::Vector2d& at, double weight) {
  if (!at.allFinite() || !(weight > 0) || std::abs(at.x()) > 1e9 || std::abs(at.y()) > 1e9) return;
  // Bayes on the odds that the line is open here: a right walk crosses only open lines, a
  // wrong one crosses open and closed alike, so the crossing multiplies them by
  // (w + (1 - w)) / (1 - w) with w the probability that the walk was right.
  const double before = Open(at);
  const double odds = before / (1 - before) / std::max(1e-6, 1 - std::min(weight, 1.0));
  const Eigen::Vector2d cell = (at / kCell_m).array().floor();
  open_[Key(static_cast<int64_t>(cell.x()), static_cast<int64_t>(cell.y()))] =
      std::min(odds / (1 + odds), 1 - 1e-6);
}

}  // namespace floorpose::tracking
