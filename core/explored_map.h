// Where the wearers have been and what they have seen: a log-odds occupancy grid in plan
// coordinates (seed 004, sections 3.3 to 3.4), and the plan's rooms they have entered.
//
// Wall points seen from a position are Bresenham rays: the cells before a point are
// evidence of free space, its own cell of a wall. The cells the wearer's body covers are
// free too. A cell's log-odds is clamped so that a long stay does not make it deaf to
// change. Grids of the same geometry merge by adding log-odds (a team's map).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include "core/floor_plan.h"
#include "core/grid.h"
#include "core/rooms.h"

namespace floorpose {

struct ExploredOptions {
  double cell_m = 0.1;
  double max_ray_m = 6.0;      // longer rays are dropped: far points are seen badly
  float hit = 0.85f;           // log-odds of p = 0.7 (seed 004, figure 10)
  float miss = -0.4f;          // log-odds of p = 0.4
  float clamp = 3.5f;          // |log-odds| at most this
  double body_radius_m = 0.3;  // the wearer's own cells are free
  int min_visit_poses = 3;     // a room is entered after this many poses in it
  double max_cells = 4e6;
};

class ExploredMap {
 public:
  // A grid over the plan's bounds and 1 m around them; rooms may be null (no room list).
  ExploredMap(const FloorPlan& plan, std::shared_ptr<const RoomMap> rooms,
              const ExploredOptions& options = {});

  // Wall points seen from `origin` (plan frame).
  void AddWalls(const Eigen::Vector2d& origin, const std::vector<Eigen::Vector2d>& points);
  // The wearer stood at `position` (plan frame).
  void AddVisit(const Eigen::Vector2d& position);
  // Adds another wearer's grid and room visits; false (nothing changed) when the grids differ.
  bool Merge(const ExploredMap& other);
  // Replaces the cells (from the wire); false when the size differs.
  bool SetLogOdds(std::vector<float> log_odds);
  void SetVisits(std::map<int, int> visits) { visits_ = std::move(visits); }

  const GridGeometry& grid() const { return grid_; }
  const std::vector<float>& log_odds() const { return log_odds_; }
  float LogOdds(const Eigen::Vector2d& p) const;  // 0 (unknown) outside the grid
  // Rooms entered (at least min_visit_poses poses in them), ascending ids.
  std::vector<int> VisitedRooms() const;
  const std::map<int, int>& visits() const { return visits_; }  // room id -> poses in it
  const RoomMap* rooms() const { return rooms_.get(); }
  // Grows with every change: publishers compare it with the value they last sent.
  uint64_t revision() const { return revision_; }

 private:
  void Add(int cell, float value);

  ExploredOptions options_;
  GridGeometry grid_;
  std::shared_ptr<const RoomMap> rooms_;
  std::vector<float> log_odds_;
  std::map<int, int> visits_;
  uint64_t revision_ = 0;
};

}  // namespace floorpose
