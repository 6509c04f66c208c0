// Square grids laid over a floor plan, and the searches the simulator's walker, the route
// planner, the room map and the explored map share on them: which cells walls come near,
// 8-connected A* without corner cutting, and the string pulling that turns a cell path
// into an any-angle polyline. Deterministic: no randomness, ties broken by cell index.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "core/floor_plan.h"

namespace floorpose {

// Cell (ix, iy) covers origin + cell_m * [ix, ix + 1) x [iy, iy + 1); its index is
// iy * nx + ix.
struct GridGeometry {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  double cell_m = 0.1;
  int nx = 0, ny = 0;

  // The grid over [min, max] grown by margin_m on every side; cells grow beyond cell_m
  // when needed to stay within max_cells.
  static GridGeometry Cover(const Eigen::Vector2d& min, const Eigen::Vector2d& max, double cell_m,
                            double margin_m, double max_cells);

  size_t size() const { return static_cast<size_t>(nx) * static_cast<size_t>(ny); }
  bool InGrid(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < nx && iy < ny; }
  int CellOf(const Eigen::Vector2d& p) const;  // -1 outside
  Eigen::Vector2d CellCentre(int cell) const {
    return origin + cell_m * Eigen::Vector2d(cell % nx + 0.5, cell / nx + 0.5);
  }
  bool operator==(const GridGeometry& o) const {
    return origin == o.origin && cell_m == o.cell_m && nx == o.nx && ny == o.ny;
  }
};

// 1 for every cell whose centre lies closer than radius_m to a wall segment (exact
// point-to-segment distances), else 0.
std::vector<uint8_t> CellsNearWalls(const GridGeometry& grid, const std::vector<Segment>& walls,
                                    double radius_m);

// 4-connected pieces of the cells where mask is set: a label per cell (-1 where unset),
// numbered in the order of their lowest cell. Returns the number of pieces.
int LabelComponents(const GridGeometry& grid, const std::vector<uint8_t>& mask,
                    std::vector<int>* labels);

// The per-cell state of a search, kept between searches: on a big grid, allocating and
// clearing it (tens of megabytes, page faults included) costs more than the search. A
// cell's entries are valid when its stamp is the current search's.
struct GridSearchScratch {
  std::vector<uint32_t> stamp;
  std::vector<double> g;
  std::vector<int> parent;
  std::vector<uint8_t> closed;
  uint32_t search = 0;

  // A new search over `cells` cells: every cell untouched, in O(1) but every 2^32nd.
  void Begin(size_t cells) {
    if (stamp.size() != cells || ++search == 0) {
      stamp.assign(cells, 0);
      g.resize(cells);
      parent.resize(cells);
      closed.resize(cells);
      search = 1;
    }
  }
  // A cell's first touch in this search: unreached, no parent, open.
  void Touch(int cell) {
    if (stamp[cell] != search) {
      stamp[cell] = search;
      g[cell] = std::numeric_limits<double>::infinity();
      parent[cell] = -1;
      closed[cell] = 0;
    }
  }
};

// The cheapest 8-connected path from start to goal through passable cells, never cutting
// a corner (a diagonal step needs both cells beside it), as cell indices from start to
// goal; empty when there is none. A step into cell q costs its length (1 or sqrt 2 cells)
// times step_weight(q), which must be at least 1 (the octile heuristic stays admissible);
// without step_weight every weight is 1. The search is guided by the octile distance to
// the goal, or by `heuristic` (cells) where that is larger: a better estimate expands
// fewer cells, and one that overestimates by e% can lengthen the path by up to e%. With
// `scratch`, its buffers are used (and kept) instead of fresh ones.
std::vector<int> GridAStar(const GridGeometry& grid, const std::vector<uint8_t>& passable,
                           int start, int goal,
                           const std::function<double(int)>& step_weight = nullptr,
                           const std::function<double(int)>& heuristic = nullptr,
                           GridSearchScratch* scratch = nullptr);

// String pulling: from each kept point, straight to the farthest later point still in
// sight. Keeps the first and the last point.
std::vector<Eigen::Vector2d> PullString(
    const std::vector<Eigen::Vector2d>& points,
    const std::function<bool(const Eigen::Vector2d&, const Eigen::Vector2d&)>& line_of_sight);

// Drops every interior point whose neighbours see each other, until none does: the kinks
// greedy string pulling leaves where a path rounds a corner in several steps.
void DropCorners(
    std::vector<Eigen::Vector2d>* path,
    const std::function<bool(const Eigen::Vector2d&, const Eigen::Vector2d&)>& line_of_sight);

// Every cell the segment a-b touches, in order from a (a supercover walk: where it passes
// exactly through a corner, both cells beside the corner too). Stops early, returning
// false, when visit returns false; cells outside the grid are passed as -1.
bool WalkSegmentCells(const GridGeometry& grid, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                      const std::function<bool(int)>& visit);

double PolylineLength(const std::vector<Eigen::Vector2d>& path);

}  // namespace floorpose
