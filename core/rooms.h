// The rooms of a floor plan: the closed regions of its free space, for the list of rooms
// a team has entered (thesis section 1.2: visited rooms are not searched twice).
//
// Plans draw a door as a gap in a wall line. Every gap between two collinear wall pieces
// up to max_door_m wide is closed by a virtual door segment; the free cells of the grid
// (no wall and no door through them) then fall into 4-connected pieces. A room is a piece
// that does not reach the grid's border (that is the outside) and has room for a person
// (a cell at least min_clearance_m from every wall). Openings wider than max_door_m
// (an open-plan area, an arch) join what they connect into one room.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/floor_plan.h"
#include "core/grid.h"

namespace floorpose {

struct RoomOptions {
  double cell_m = 0.1;
  double max_door_m = 1.6;  // widest gap closed as a door (double doors are about 1.5 m)
  // Two wall pieces are in one line when the gap runs within this angle of both and
  // their offset across it is below max_door_offset_m.
  double door_angle_rad = 0.26;  // 15 degrees
  double max_door_offset_m = 0.1;
  double min_clearance_m = 0.4;
  double max_cells = 16e6;
};

struct Room {
  int id = 0;                                        // 0, 1, ... in the order of their lowest cell
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // a point inside, near the centroid
  double area_m2 = 0;
};

class RoomMap {
 public:
  explicit RoomMap(const FloorPlan& plan, const RoomOptions& options = {});

  int RoomAt(const Eigen::Vector2d& p) const;  // -1: a wall, a doorway, outside
  const std::vector<Room>& rooms() const { return rooms_; }
  const std::vector<Segment>& doors() const { return doors_; }
  const GridGeometry& grid() const { return grid_; }

 private:
  GridGeometry grid_;
  std::vector<Segment> doors_;
  std::vector<int> labels_;  // room id per cell, or -1
  std::vector<Room> rooms_;
};

}  // namespace floorpose
