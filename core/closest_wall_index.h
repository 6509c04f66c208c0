// "Which wall is closest to this point?" in O(1): a uniform grid over the plan where each
// cell lists the only segments that can be closest to any point inside it.
//
// Exactness: let c be a cell's centre, r its half-diagonal and d* the distance from c to
// the nearest segment. For any q in the cell, the closest segment s satisfies
// d(s, c) <= d(s, q) + r <= d*(q) + r <= d* + 2r. So the candidates {s : d(s, c) <= d* + 2r}
// always contain the answer. Cells farther than `max_distance_m` from every wall store
// nothing: queries there answer "no wall in range", which is all registration needs.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "core/distance_grid.h"
#include "core/floor_plan.h"

namespace floorpose {

struct ClosestWall {
  uint32_t segment = 0;
  Eigen::Vector2d point;   // closest point on the segment
  Eigen::Vector2d normal;  // unit normal of the segment
  double distance = 0.0;
};

class ClosestWallIndex {
 public:
  struct Options {
    // Grid resolution. A cell lists the segments within its diagonal of its nearest, so
    // smaller cells keep the lists short where a plan has many short segments (a wall
    // drawn in many pieces, a raster plan's corners), at 8 bytes a cell.
    double cell_m = 0.1;
    double max_distance_m = 3.0;  // beyond this, queries return nothing
    // The distance grid's cells (Distance; 2 bytes a cell), 0 for none.
    double grid_cell_m = 0.05;
  };
  // How near a wall the distance grid answers: a wall point 1 m off its wall is
  // clutter to the measurement model (e^-50 of the hit density at its 0.1 m noise).
  static constexpr double kGridNearM = 1.0;

  ClosestWallIndex(const FloorPlan& plan, Options options);
  explicit ClosestWallIndex(const FloorPlan& plan) : ClosestWallIndex(plan, Options{}) {}

  // The closest wall within max_distance_m, or nothing.
  std::optional<ClosestWall> Query(const Eigen::Vector2d& p) const;

  // The distance from p to the closest wall: from the distance grid within kGridNearM of a
  // wall (within a few millimetres, see core/distance_grid.h), otherwise as Query
  // answers it; infinity beyond max_distance_m, and beyond far_m where the distance grid
  // shows it without a search (for a caller to whom all such distances are alike).
  double Distance(const Eigen::Vector2d& p,
                  double far_m = std::numeric_limits<double>::infinity()) const {
    double at_least = 0;
    if (const std::optional<double> d = grid_.Near(p, &at_least)) return *d;
    if (at_least >= far_m) return std::numeric_limits<double>::infinity();
    const std::optional<ClosestWall> hit = Query(p);
    return hit ? hit->distance : std::numeric_limits<double>::infinity();
  }

  // Whether the step p -> q properly crosses a wall (touching does not count), from the
  // candidate lists: exact, in pieces no longer than a cell (any wall across a piece is
  // close enough to its middle for the middle's cell to list it). For every sample of the
  // belief at every step.
  bool StepCrossesWall(const Eigen::Vector2d& p, const Eigen::Vector2d& q) const;

  const FloorPlan& plan() const { return plan_; }
  double max_distance_m() const { return options_.max_distance_m; }
  const Options& options() const { return options_; }
  size_t MemoryBytes() const;
  size_t cells() const { return cells_.size(); }

 private:
  // What a query needs of a segment, precomputed: a, b - a, 1 / |b - a|^2, unit normal.
  struct SegmentData {
    Eigen::Vector2d a, d, normal;
    double inv_len2;
    // The squared distance from p, and where along the segment (0 at a, 1 at b).
    double Distance2(const Eigen::Vector2d& p, double* u_out = nullptr) const {
      const Eigen::Vector2d ap = p - a;
      const double u = std::clamp(ap.dot(d) * inv_len2, 0.0, 1.0);
      if (u_out) *u_out = u;
      return (ap - u * d).squaredNorm();
    }
  };

  // A cell's candidates, nearest its centre first. Nine queries in ten at a plan's walls
  // find one or two (MLSTRUCT 848), which the cell holds itself: one cache line.
  //   none:           a = b = kNone
  //   one:            a = the segment, b = kNone
  //   two:            a, b = the segments
  //   three or more:  a = where they start in lists_, b = kList | their count
  // (segment indices are below kList: a plan of 2^31 segments would not fit in memory).
  struct Cell {
    uint32_t a, b;
  };
  static constexpr uint32_t kList = 0x80000000u, kNone = 0xFFFFFFFFu;
  // The candidates of a cell as a range: its own (`held`, filled) or its list's.
  std::pair<const uint32_t*, const uint32_t*> Candidates(const Cell& cell, uint32_t held[2]) const {
    if (cell.b != kNone && (cell.b & kList)) {
      const uint32_t* begin = lists_.data() + cell.a;
      return {begin, begin + (cell.b & ~kList)};
    }
    held[0] = cell.a;
    held[1] = cell.b;
    return {held, held + (cell.a == kNone ? 0 : cell.b == kNone ? 1 : 2)};
  }

  // Building the index: the cells (coarser where the plan is too large for options' size,
  // within kMaxCells); each cell's candidate segments, sorted nearest first, in `lists`
  // from `begin[i]` to `begin[i + 1]`; then the cells as they are kept.
  void SizeCells();
  void FillCandidates(std::vector<uint32_t>* begin, std::vector<uint32_t>* lists) const;
  void SortCandidates(const std::vector<uint32_t>& begin, std::vector<uint32_t>* lists) const;
  void PackCells(const std::vector<uint32_t>& begin, const std::vector<uint32_t>& lists);

  // The cell holding p, false outside the grid (or for NaN). A point a rounding away from
  // its cell may take the next: a list holds for its cell grown by far more than that
  // (FillCandidates' slack), and StepCrossesWall's walls are within 0.2 cells of that.
  bool CellOf(const Eigen::Vector2d& p, int* ix, int* iy) const {
    const double fx = (p.x() - origin_.x()) * per_cell_;
    const double fy = (p.y() - origin_.y()) * per_cell_;
    if (!(fx >= 0 && fy >= 0 && fx < nx_ && fy < ny_)) return false;
    *ix = static_cast<int>(fx);
    *iy = static_cast<int>(fy);
    return true;
  }

  // The centre of cell (ix, iy): what the lists are sorted by and Query bounds from, so
  // one formula for both.
  Eigen::Vector2d CellCentre(int ix, int iy) const {
    return {origin_.x() + (ix + 0.5) * options_.cell_m, origin_.y() + (iy + 0.5) * options_.cell_m};
  }

  FloorPlan plan_;
  Options options_;
  std::vector<SegmentData> data_;
  Eigen::Vector2d origin_;
  double per_cell_ = 0;  // 1 / options_.cell_m: a query multiplies rather than divides
  int nx_ = 0, ny_ = 0;
  std::vector<Cell> cells_;      // row by row, nx_ a row
  std::vector<uint32_t> lists_;  // the candidates of the cells with three or more
  DistanceGrid grid_;
};

// The same answer by trying every segment: the oracle for tests and the baseline for
// benchmarks.
std::optional<ClosestWall> BruteForceClosestWall(const FloorPlan& plan, const Eigen::Vector2d& p,
                                                 double max_distance_m);

}  // namespace floorpose
