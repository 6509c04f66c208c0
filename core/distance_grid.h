// The distance to the closest wall near the walls in O(1): a fine grid read by bilinear
// interpolation, for the question the belief's measurement model asks of every wall point
// at every sample (the likelihood field of Probabilistic Robotics, section 6.4).
//
// It holds the squared distance at the cells' centres. d^2 is smooth across a wall line (a
// parabola along its normal), so interpolating it errs by at most cell^2 / 4 along a wall
// and cell^2 / 2 about its ends: at 5 cm cells a point on a wall reads at most 2.5 cm off
// it (3.5 cm at an end), one 10 cm off at most 10.3 cm. Interpolating d instead would
// read half a cell off at the wall, a kink no grid resolves. Where two walls' distances
// meet, the error is at most the slope 2 d times the cell.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/floor_plan.h"
#include "core/grid.h"

namespace floorpose {

class DistanceGrid {
 public:
  DistanceGrid() = default;  // holds nothing: no point is near
  // Cells of cell_m (coarser if the plan needs more than max_cells) over the plan and
  // near_m about it, each with its centre's squared distance to the closest wall when
  // that is within near_m.
  DistanceGrid(const std::vector<Segment>& walls, const Eigen::Vector2d& min,
               const Eigen::Vector2d& max, double cell_m, double near_m, double max_cells);

  // The distance from p to the closest wall, interpolated between the four cell centres
  // about p, when all four are within near_m of a wall; otherwise nothing, and in
  // *at_least (when given) a distance no wall is nearer p than: from the nearest centre
  // beyond near_m, or beyond the grid from the walls' bounding box (0 where neither tells).
  std::optional<double> Near(const Eigen::Vector2d& p, double* at_least = nullptr) const;

  size_t MemoryBytes() const { return d2_.size() * sizeof(uint16_t); }

 private:
  static constexpr uint16_t kFar = 0xffff;

  // The lower bounds *at_least for a point Near does not answer: beyond the cell centres,
  // from the walls' box; among them, from the nearest of the four centres marked far (p at
  // (tx, ty) cells from the first).
  double BoxBound(const Eigen::Vector2d& p) const;
  double FarCentreBound(const uint16_t corners[4], double tx, double ty) const;

  GridGeometry grid_;
  double near_m_ = 0;
  Eigen::Vector2d walls_min_ = Eigen::Vector2d::Zero(), walls_max_ = Eigen::Vector2d::Zero();
  std::vector<uint16_t> d2_;  // d^2 / near_m^2 in 1/65534ths; kFar beyond near_m
};

}  // namespace floorpose
