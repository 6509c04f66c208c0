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
#include <cmath>
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
    // smaller cells keep the lists short where a plan has many short segments (a raster
    // plan's pixel edges), at 8 bytes a cell.
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
  std::optional<ClosestWall> Query(const Eigen::Vector2d& p) const {
    const Cell* cell = CellAt(p);
    if (!cell || cell->segment[0] == kNone) return std::nullopt;
    if (cell->segment[0] == kList) return QueryList(*cell, p);
    // One or two candidates, held in the cell: the nearer, ties to the higher index.
    const uint32_t k0 = cell->segment[0], k1 = cell->segment[1];
    double u0 = 0, u1 = 0;
    const double d0 = data_[k0].Distance2(p, &u0), d1 = data_[k1].Distance2(p, &u1);
    const bool second = d1 < d0 || (d1 == d0 && k1 > k0);
    return Hit(second ? k1 : k0, second ? d1 : d0, second ? u1 : u0);
  }

  // The distance from p to the closest wall: from the distance grid within kGridNearM of a
  // wall (within a few millimetres, see core/distance_grid.h), otherwise as Query
  // answers it; infinity beyond max_distance_m.
  double Distance(const Eigen::Vector2d& p) const {
    if (const std::optional<double> d = grid_.Near(p)) return *d;
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

  // A cell's candidate segments. One or two are held in the cell itself (segment[1] ==
  // segment[0] for one): a query there, nine in ten near walls, reads 8 bytes of the grid
  // and two segments, with no branch on the count. A longer list, nearest the cell's
  // centre first: segment[0] is kList and candidates_[segment[1]] its length, the
  // segments after it. kNone: no wall within max_distance_m.
  static constexpr uint32_t kNone = 0xffffffff, kList = 0xfffffffe;
  struct Cell {
    uint32_t segment[2] = {kNone, kNone};
  };
  // A cell's candidates and their count.
  std::pair<const uint32_t*, uint32_t> Candidates(const Cell& cell) const {
    if (cell.segment[0] == kNone) return {nullptr, 0};
    if (cell.segment[0] == kList)
      return {candidates_.data() + cell.segment[1] + 1, candidates_[cell.segment[1]]};
    return {cell.segment, cell.segment[0] == cell.segment[1] ? 1u : 2u};
  }
  // The cell holding p, or nullptr outside the grid (or for NaN).
  const Cell* CellAt(const Eigen::Vector2d& p) const {
    const double fx = (p.x() - origin_.x()) / options_.cell_m;
    const double fy = (p.y() - origin_.y()) / options_.cell_m;
    if (!(fx >= 0 && fy >= 0 && fx < nx_ && fy < ny_)) return nullptr;
    return &cells_[static_cast<size_t>(static_cast<int>(fy)) * nx_ + static_cast<int>(fx)];
  }
  // Segment k as the closest wall, d2 away at u along it, if within max_distance_m.
  std::optional<ClosestWall> Hit(uint32_t k, double d2, double u) const {
    if (!(d2 < options_.max_distance_m * options_.max_distance_m)) return std::nullopt;
    const SegmentData& s = data_[k];
    return ClosestWall{k, s.a + u * s.d, s.normal, std::sqrt(d2)};
  }
  // Query in a cell with more than two candidates.
  std::optional<ClosestWall> QueryList(const Cell& cell, const Eigen::Vector2d& p) const;

  // Building the index: the cells (coarser where the plan is too large for options' size,
  // within kMaxCells); each cell's candidate segments (CSR: list[begin[i] .. begin[i+1]));
  // each list sorted nearest first; then the cells as Query reads them.
  struct CandidateLists {
    std::vector<uint32_t> begin, list;
  };
  void SizeCells();
  CandidateLists FillCandidates() const;
  void SortCandidates(CandidateLists* lists) const;
  void StoreCells(const CandidateLists& lists);

  // The centre of cell (ix, iy): what the lists are sorted by and Query bounds from, so
  // one formula for both.
  Eigen::Vector2d CellCentre(int ix, int iy) const {
    return {origin_.x() + (ix + 0.5) * options_.cell_m, origin_.y() + (iy + 0.5) * options_.cell_m};
  }

  FloorPlan plan_;
  Options options_;
  std::vector<SegmentData> data_;
  Eigen::Vector2d origin_;
  int nx_ = 0, ny_ = 0;
  std::vector<Cell> cells_;           // row-major, nx_ by ny_
  std::vector<uint32_t> candidates_;  // the lists of cells with more than two
  DistanceGrid grid_;
};

// The same answer by trying every segment: the oracle for tests and the baseline for
// benchmarks.
std::optional<ClosestWall> BruteForceClosestWall(const FloorPlan& plan, const Eigen::Vector2d& p,
                                                 double max_distance_m);

}  // namespace floorpose
