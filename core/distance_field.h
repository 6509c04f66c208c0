// The distance to the closest plan wall as a field sampled on a square lattice, so that
// the measurement model's one question per wall point ("how far is the nearest wall?")
// costs two cache lines instead of a walk through a candidate list: the likelihood field
// of Probabilistic Robotics (section 6.4) as AMCL keeps it, but interpolated.
//
// The exact distance is stored at every node (16 bits, in 1/65535 of the reach), and a
// query blends the four nodes around it bilinearly. Distance is 1-Lipschitz, so the blend
// is off by at most 0.71 of a cell (at a cell's centre); along a straight wall it is
// linear in each axis, so the blend is exact there but in the cells the wall crosses.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace floorpose {

class ClosestWallIndex;

class DistanceField {
 public:
  DistanceField() = default;
  // Over the index's plan and its reach around it, nodes cell_m apart; the distances are
  // the index's exact ones, capped at its max_distance_m.
  DistanceField(const ClosestWallIndex& index, double cell_m);

  bool empty() const { return values_.empty(); }
  // The distance at p, at most the reach (also outside the field and for NaN).
  double Distance(const Eigen::Vector2d& p) const {
    const double fx = (p.x() - origin_.x()) * inv_cell_;
    const double fy = (p.y() - origin_.y()) * inv_cell_;
    if (!(fx >= 0 && fy >= 0 && fx < nx_ - 1 && fy < ny_ - 1)) return reach_m_;  // also NaN
    const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
    const double tx = fx - ix, ty = fy - iy;
    const uint16_t* row = values_.data() + static_cast<size_t>(iy) * static_cast<size_t>(nx_) + ix;
    const double lower = row[0] + tx * (row[1] - row[0]);
    const double upper = row[nx_] + tx * (row[nx_ + 1] - row[nx_]);
    return (lower + ty * (upper - lower)) * step_m_;
  }
  double cell_m() const { return cell_m_; }
  size_t MemoryBytes() const { return values_.size() * sizeof(uint16_t); }

 private:
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();
  double cell_m_ = 0, inv_cell_ = 0;
  double reach_m_ = 0, step_m_ = 0;  // the cap, and the distance of one unit
  int nx_ = 0, ny_ = 0;
  std::vector<uint16_t> values_;  // node (ix, iy) at origin + cell_m * (ix, iy)
};

}  // namespace floorpose
