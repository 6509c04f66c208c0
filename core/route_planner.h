// Routes on a floor plan (seed 003's minimap routes): the shortest path a person of a
// given body radius can walk from one plan position to another, through door openings,
// never closer to a wall than that radius.
//
// The plan's free space is a grid. A cell is passable when no wall comes within the body
// radius plus half the cell's diagonal of its centre, so every point of a passable cell
// keeps the body radius: a polyline that stays in passable cells is clear, exactly, not
// just at its samples. A route is 8-connected A* on that grid, pulled tight by
// line-of-sight shortcuts (any angle, checked cell by cell along each leg), so it bends
// only at corners and is within a few percent of the true shortest path. The grid is
// built once per plan (tens of milliseconds); a route takes milliseconds.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "core/floor_plan.h"
#include "core/grid.h"

namespace floorpose {

struct RouteOptions {
  double cell_m = 0.05;        // grid resolution
  double body_radius_m = 0.3;  // the route keeps this far from every wall
  // A start or destination closer to a wall than the body radius (a wearer standing at a
  // wall, a destination picked on one) moves to the nearest passable point within this.
  double snap_m = 1.0;
  double max_cells = 16e6;  // larger plans get coarser cells (64 MB of grid at most)
};

struct Route {
  std::string error;                  // why there is no route; empty when there is one
  std::vector<Eigen::Vector2d> path;  // from the start to the destination, plan metres
  double length_m = 0;
  double start_moved_m = 0, goal_moved_m = 0;  // snapped away from a wall by this much
  bool ok() const { return error.empty(); }
};

// A disc a route keeps out of (a hazard, a blocked exit), plan metres. The route's body
// keeps clear of it as of a wall.
struct KeepOut {
  Eigen::Vector2d centre;
  double radius_m = 1.0;
};

class RoutePlanner {
 public:
  RoutePlanner(const FloorPlan& plan, const RouteOptions& options = {});

  // A route from `from` to `to`, or the reason there is none (outside the plan, in a
  // wall, or no opening at least twice the body radius wide leads there).
  // Keep-outs that hold `from` are left out: a wearer standing in one walks out of it.
  Route Plan(const Eigen::Vector2d& from, const Eigen::Vector2d& to,
             const std::vector<KeepOut>& keep_out = {}) const;
  // The way out: the shortest route to one of the plan's exits, or on a plan without
  // them to its stairs (the way down); the reason when there is none. An exit inside a
  // keep-out is not a way out.
  Route WayOut(const Eigen::Vector2d& from, const std::vector<KeepOut>& keep_out = {}) const;
  // Through `via` in order, then to `to`: each leg a route of its own. A waypoint that
  // cannot be reached (in a keep-out, beyond a new wall) is passed over; the route then
  // goes on to the next.
  Route Through(const Eigen::Vector2d& from, const std::vector<Eigen::Vector2d>& via,
                const Eigen::Vector2d& to, const std::vector<KeepOut>& keep_out = {}) const;
  const std::vector<Eigen::Vector2d>& exits() const { return exits_; }

  const RouteOptions& options() const { return options_; }
  const GridGeometry& grid() const { return grid_; }
  bool Passable(int cell) const { return cell >= 0 && passable_[cell]; }
  // Every point of the segment a-b lies in a passable cell.
  bool LineOfSight(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;

 private:
  // The cell nearest p within snap_m that is passable in `passable` (and of the given
  // component when >= 0), or -1.
  int Snap(const std::vector<uint8_t>& passable, const Eigen::Vector2d& p, int component) const;
  // Why there is no route from `from` to `to` before any search: a position that is not
  // one or outside the plan, a destination in a keep-out. Empty when there is none.
  std::string Refusal(const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                      const std::vector<KeepOut>& keep_out) const;
  // The route on `passable` (passable_, or it with keep-outs), once Refusal found nothing.
  Route Search(const std::vector<uint8_t>& passable, const Eigen::Vector2d& from,
               const Eigen::Vector2d& to) const;
  // Search's path through the A* cells, from `from` to `to`, pulled tight where the
  // straight legs are clear; a start or goal snapped off a wall keeps its leg to it.
  void ShapePath(const std::vector<int>& cells, const std::vector<uint8_t>& passable,
                 const Eigen::Vector2d& from, const Eigen::Vector2d& to, int goal,
                 Route* route) const;
  // passable_ less the cells a body centred in them would reach into a keep-out.
  std::vector<uint8_t> WithKeepOuts(const Eigen::Vector2d& from,
                                    const std::vector<KeepOut>& keep_out) const;
  // Distances to the goal on the coarse grid (Dijkstra, coarse cells), for A*'s estimate:
  // exact up to a bit beyond the start's, and that bound (a lower one) beyond.
  std::vector<float> CoarseDistances(int goal, int start) const;

  RouteOptions options_;
  std::vector<Eigen::Vector2d> exits_;  // the middles of the exits (or stairs' lines)
  GridGeometry grid_;
  std::vector<uint8_t> passable_;
  std::vector<int> component_;  // LabelComponents of passable_
  // A* is guided by shortest distances on a grid kCoarse times coarser, where a cell is
  // open when any of its cells is passable: in a building, the straight-line estimate
  // sends A* into every room on the way, this one round them, about 20 times fewer
  // cells expanded. Two coarse diagonals are taken off, so it stays an underestimate
  // except where walls force detours smaller than that.
  static constexpr int kCoarse = 4;
  GridGeometry coarse_;
  std::vector<uint8_t> coarse_open_;
  // One search at a time, on buffers kept between them (GridSearchScratch).
  mutable std::mutex search_mutex_;
  mutable GridSearchScratch scratch_;
};

}  // namespace floorpose
