// Synthetic floor plans for the simulator tests, built in code so that the tests need no
// data set: an office corridor with rooms on both sides and, optionally, a hall at its end.
#pragma once

#include <vector>

#include "core/floor_plan.h"

namespace floorpose::testing {

// A corridor 2 m wide (y in [0, 2]) and 5 m per room long, rooms of 5 x 4 m on both sides,
// each with a door of 1 m in the corridor wall; at the east end either a closing wall or,
// with hall_m >= 10, a square hall of hall_m, open to the corridor. Single-line walls.
inline FloorPlan SyntheticOffice(int rooms_per_side = 6, double hall_m = 0.0) {
  std::vector<Segment> s;
  auto wall = [&](double x0, double y0, double x1, double y1) {
    s.push_back({{x0, y0}, {x1, y1}});
  };
  const double end = 5.0 * rooms_per_side;
  for (int i = 0; i < rooms_per_side; ++i) {
    const double x = 5.0 * i;
    wall(x, 2, x + 2, 2), wall(x + 3, 2, x + 5, 2);  // north corridor wall, door in the middle
    wall(x, 0, x + 2, 0), wall(x + 3, 0, x + 5, 0);  // south corridor wall
    if (i > 0) wall(x, 2, x, 6), wall(x, 0, x, -4);  // between rooms
  }
  wall(0, 6, end, 6), wall(0, -4, end, -4), wall(0, -4, 0, 6);
  if (hall_m < 10.0) {
    wall(end, -4, end, 6);
  } else {
    const double lo = 1.0 - hall_m / 2, hi = 1.0 + hall_m / 2;
    wall(end, lo, end, 0), wall(end, 2, end, hi);
    wall(end, lo, end + hall_m, lo), wall(end + hall_m, lo, end + hall_m, hi);
    wall(end, hi, end + hall_m, hi);
  }
  return MakeFloorPlan("synthetic-office", std::move(s)).plan;
}

}  // namespace floorpose::testing
