// Checks for routes shared by the synthetic and the real-plan tests: the distance a path
// keeps from the walls, and a brute-force shortest path on the planner's own grid.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <queue>
#include <utility>
#include <vector>

#include "core/floor_plan.h"
#include "core/route_planner.h"

namespace floorpose::testing {

// The smallest distance between two segments (they do not cross: that is 0).
inline double SegmentDistance(const Segment& p, const Segment& q) {
  auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() * b.y() - a.y() * b.x();
  };
  const Eigen::Vector2d r = p.b - p.a, s = q.b - q.a;
  const double d1 = cross(r, q.a - p.a), d2 = cross(r, q.b - p.a);
  const double d3 = cross(s, p.a - q.a), d4 = cross(s, p.b - q.a);
  if (((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0))) return 0.0;
  return std::min(
      {(ClosestPointOnSegment(q, p.a) - p.a).norm(), (ClosestPointOnSegment(q, p.b) - p.b).norm(),
       (ClosestPointOnSegment(p, q.a) - q.a).norm(), (ClosestPointOnSegment(p, q.b) - q.b).norm()});
}

// The closest any leg of the path comes to any wall (0 when it crosses one).
inline double PathClearance(const std::vector<Eigen::Vector2d>& path,
                            const std::vector<Segment>& walls) {
  double closest = std::numeric_limits<double>::infinity();
  for (size_t i = 1; i < path.size(); ++i)
    for (const Segment& w : walls)
      closest = std::min(closest, SegmentDistance({path[i - 1], path[i]}, w));
  return closest;
}

// Brute force: Dijkstra over every passable cell of the planner's grid with 32 step
// directions (every (dx, dy) up to 3 cells with no common divisor), each step checked
// with the planner's line of sight. Between cell centres of the start's and the goal's
// cells; its lengths are at most 1.3% above the true shortest path on that grid.
struct Reference {
  double centres_m = 0;  // between the centres of the start's and the goal's cells
  double ends_m = 0;     // from the exact ends to those centres: the slack either way
};
inline Reference BruteForceShortest(const RoutePlanner& planner, const Eigen::Vector2d& from,
                                    const Eigen::Vector2d& to) {
  const GridGeometry& g = planner.grid();
  const int start = g.CellOf(from), goal = g.CellOf(to);
  std::vector<std::pair<int, int>> steps;
  for (int dy = -3; dy <= 3; ++dy)
    for (int dx = -3; dx <= 3; ++dx)
      if ((dx || dy) && std::gcd(std::abs(dx), std::abs(dy)) == 1) steps.push_back({dx, dy});
  std::vector<double> dist(g.size(), std::numeric_limits<double>::infinity());
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  dist[start] = 0;
  open.push({0.0, start});
  while (!open.empty()) {
    const auto [d, c] = open.top();
    open.pop();
    if (d > dist[c]) continue;
    if (c == goal) break;
    const int x = c % g.nx, y = c / g.nx;
    for (const auto& [dx, dy] : steps) {
      if (!g.InGrid(x + dx, y + dy)) continue;
      const int q = (y + dy) * g.nx + x + dx;
      const double nd = d + g.cell_m * std::hypot(dx, dy);
      if (!planner.Passable(q) || nd >= dist[q]) continue;
      if (!planner.LineOfSight(g.CellCentre(c), g.CellCentre(q))) continue;
      dist[q] = nd;
      open.push({nd, q});
    }
  }
  return {dist[goal], (from - g.CellCentre(start)).norm() + (to - g.CellCentre(goal)).norm()};
}

}  // namespace floorpose::testing
