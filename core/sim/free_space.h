// Where a person can walk on a floor plan, for the simulator: the walls rasterised onto a
// grid, the distance from every cell to the nearest wall (clearance), and the walkable
// region: cells at least a body radius from any wall, indoors, in one connected piece.
// Paths between two points come from A* on that grid, shortened by line-of-sight
// shortcuts ("string pulling"). Everything is deterministic: no randomness in here.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/floor_plan.h"
#include "core/grid.h"

namespace floorpose::sim {

struct FreeSpaceOptions {
  double cell_m = 0.1;         // grid resolution
  double body_radius_m = 0.3;  // a walker's centre stays this far from walls and objects
  double margin_m = 1.0;       // grid beyond the plan's bounds
  // Indoors: of `indoor_rays` rays cast from a cell, at most `max_escaping_rays` leave the
  // grid without meeting a wall. Cheap, and it works for plans whose outline has a gap
  // (an open corridor end) where a flood fill from outside would leak in.
  int indoor_rays = 16;
  int max_escaping_rays = 2;
  // Many plans (e.g. mlstruct) draw only inner walls, without an outline: then (almost)
  // nothing is indoors by the test above, and the walkable region is the free space inside
  // the plan's bounding box. Used when the enclosed region is smaller than this share of it.
  double min_indoor_share = 0.25;
  // A* prefers the middle of corridors: a step costs up to (1 + centre_weight) times its
  // length when its cell is closer than centre_clearance_m to a wall.
  double centre_weight = 2.0;
  double centre_clearance_m = 1.0;
};

class FreeSpace {
 public:
  // `walls` are everything the walker must not cross (the plan's walls); `min`/`max` the
  // plan's bounds.
  FreeSpace(const std::vector<Segment>& walls, const Eigen::Vector2d& min,
            const Eigen::Vector2d& max, const FreeSpaceOptions& options);

  bool empty() const { return cells_.empty(); }
  // How the walkable region was chosen, for the simulation's description.
  const std::string& region() const { return region_; }
  const FreeSpaceOptions& options() const { return options_; }
  double walkable_area_m2() const;
  // Walkable cells, ascending.
  const std::vector<int>& cells() const { return cells_; }
  Eigen::Vector2d CellCentre(int cell) const;
  int CellOf(const Eigen::Vector2d& p) const;  // -1 outside the grid

  bool Walkable(const Eigen::Vector2d& p) const;
  double Clearance(const Eigen::Vector2d& p) const;  // metres to the nearest wall (or object)
  // The walkable cell farthest from any wall (the first of equals); -1 when empty.
  int MostOpenCell() const;

  // Blocks the cells an object standing on the floor covers (its footprint polygon grown by
  // the body radius), unless that would cut the walkable region into pieces. Returns
  // whether it blocked.
  bool BlockIfConnected(const std::vector<Eigen::Vector2d>& footprint);
  // Keeps only the walkable cells with at least `min_clearance_m` connected to `cell` (the
  // hall scenario). Nothing changes when `cell` itself is not kept.
  void RestrictTo(int cell, double min_clearance_m);

  // Every point of the straight line a-b lies in a walkable cell.
  bool LineOfSight(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  // A centre-preferring shortest path (8-connected A*, no corner cutting) from `from` to
  // `to`, shortened by line-of-sight shortcuts. Its first point is `from`, its last `to`.
  // Empty when either end is not walkable or `to` cannot be reached.
  std::vector<Eigen::Vector2d> Path(const Eigen::Vector2d& from, const Eigen::Vector2d& to) const;

 private:
  bool InGrid(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < nx_ && iy < ny_; }
  // Cells reachable from `seed` through cells where mask is set (4-connected).
  size_t Reach(int seed, const std::vector<uint8_t>& mask, std::vector<int>* out) const;
  // Whether the walkable cells of `ring` reach each other inside the window [x0, x1] x
  // [y0, y1] (cells; clipped to the grid).
  bool LocallyConnected(const std::vector<int>& ring, int x0, int y0, int x1, int y1) const;
  // The construction's steps: every cell a wall passes through (sampled at half a cell);
  // each cell's distance to the nearest of those, metres; the cells indoors (rays from a
  // block's walkable cell meet walls in enough directions); and the region to walk in,
  // the largest enclosed free region, or the plan's bounding box where it has no closed
  // outline (cells_, walkable_, region_).
  std::vector<uint8_t> BlockedCells(const std::vector<Segment>& walls) const;
  std::vector<float> Clearance(const std::vector<uint8_t>& blocked) const;
  std::vector<uint8_t> IndoorCells(const std::vector<uint8_t>& free) const;
  void ChooseRegion(const std::vector<uint8_t>& free, const std::vector<uint8_t>& indoor,
                    const Eigen::Vector2d& min, const Eigen::Vector2d& max);

  FreeSpaceOptions options_;
  Eigen::Vector2d origin_;  // corner of cell (0, 0)
  int nx_ = 0, ny_ = 0;
  std::vector<float> clearance_;   // metres, per cell
  std::vector<uint8_t> walkable_;  // per cell
  std::vector<int> cells_;
  std::string region_;
};

// Whether p lies inside a simple polygon (even-odd rule), and its distance to the
// polygon (0 inside).
bool InsidePolygon(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p);
double DistanceToPolygon(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p);

}  // namespace floorpose::sim
