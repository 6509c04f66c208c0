// The wearer's own way back: the path walked, in the slam frame, one point every
// `spacing_m`, for the whole walk in bounded memory (when full, every other point goes and
// the spacing doubles: a long walk keeps its shape, coarser). The plan's way back is these
// points under the alignment in use, so a correction of the alignment moves the whole path
// with it, as PlanTrack does.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

namespace floorpose {

class Breadcrumbs {
 public:
  struct Crumb {
    Eigen::Vector2d slam;  // metres
    std::string floor;
  };
  explicit Breadcrumbs(double spacing_m = 0.5, size_t capacity = 8192);

  // The wearer at `slam` on `floor`: kept when it is `spacing()` from the last crumb, or on
  // another floor.
  void Add(const Eigen::Vector2d& slam, const std::string& floor);
  void Clear() { crumbs_.clear(); }

  // Oldest first.
  const std::vector<Crumb>& crumbs() const { return crumbs_; }
  double spacing() const { return spacing_m_; }
  // The crumbs since the wearer last came onto `floor`, newest first: the way back on it.
  std::vector<Eigen::Vector2d> WayBackOn(const std::string& floor) const;

 private:
  double spacing_m_;
  size_t capacity_;
  std::vector<Crumb> crumbs_;
};

}  // namespace floorpose
