#include "core/breadcrumbs.h"

#include <algorithm>

namespace floorpose {

Breadcrumbs::Breadcrumbs(double spacing_m, size_t capacity)
    : spacing_m_(spacing_m), capacity_(std::max<size_t>(capacity, 4)) {}

void Breadcrumbs::Add(const Eigen::Vector2d& slam, const std::string& floor) {
  if (!slam.allFinite()) return;
  if (!crumbs_.empty() && crumbs_.back().floor == floor &&
      (crumbs_.back().slam - slam).norm() < spacing_m_)
    return;
  if (crumbs_.size() == capacity_) {
    // Every other crumb goes, but never the first (the entry) nor one where the floor
    // changes (the stairs).
    std::vector<Crumb> kept;
    kept.reserve(capacity_);
    for (size_t i = 0; i < crumbs_.size(); ++i) {
      const bool floor_edge = i > 0 && crumbs_[i].floor != crumbs_[i - 1].floor;
      if (i % 2 == 0 || floor_edge) kept.push_back(crumbs_[i]);
    }
    crumbs_ = std::move(kept);
    spacing_m_ *= 2;
  }
  crumbs_.push_back({slam, floor});
}

std::vector<Eigen::Vector2d> Breadcrumbs::WayBackOn(const std::string& floor) const {
  std::vector<Eigen::Vector2d> back;
  for (auto it = crumbs_.rbegin(); it != crumbs_.rend() && it->floor == floor; ++it)
    back.push_back(it->slam);
  return back;
}

}  // namespace floorpose
