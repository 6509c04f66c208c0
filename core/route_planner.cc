#include "core/route_planner.h"

#include <cmath>
#include <cstdio>
#include <limits>

namespace floorpose {

RoutePlanner::RoutePlanner(const FloorPlan& plan, const RouteOptions& options)
    : options_(options) {
  // No margin: a route stays within the plan's bounds.
  grid_ = GridGeometry::Cover(plan.min, plan.max, options_.cell_m, 0.0, options_.max_cells);
  const double keep = options_.body_radius_m + grid_.cell_m * M_SQRT1_2;
  passable_ = CellsNearWalls(grid_, plan.segments, keep);
  for (size_t i = 0; i < passable_.size(); ++i) {
    const Eigen::Vector2d c = grid_.CellCentre(static_cast<int>(i));
    const bool inside = (c.array() >= plan.min.array()).all() && (c.array() <= plan.max.array()).all();
    passable_[i] = !passable_[i] && inside;
  }
  LabelComponents(grid_, passable_, &component_);
}

bool RoutePlanner::LineOfSight(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  return WalkSegmentCells(grid_, a, b, [this](int cell) { return Passable(cell); });
}

int RoutePlanner::Snap(const Eigen::Vector2d& p, int component) const {
  const int reach = static_cast<int>(std::ceil(options_.snap_m / grid_.cell_m));
  const Eigen::Vector2d f = (p - grid_.origin) / grid_.cell_m;
  const int cx = static_cast<int>(std::floor(f.x())), cy = static_cast<int>(std::floor(f.y()));
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (int y = cy - reach; y <= cy + reach; ++y)
    for (int x = cx - reach; x <= cx + reach; ++x) {
      if (!grid_.InGrid(x, y)) continue;
      const int cell = y * grid_.nx + x;
      if (!passable_[cell] || (component >= 0 && component_[cell] != component)) continue;
      const double d = (grid_.CellCentre(cell) - p).norm();
      if (d <= options_.snap_m && d < best_d) best = cell, best_d = d;
    }
  return best;
}

Route RoutePlanner::Plan(const Eigen::Vector2d& from, const Eigen::Vector2d& to) const {
  Route route;
  char text[256];
  auto fail = [&](const char* format, double a, double b) {
    std::snprintf(text, sizeof(text), format, a, b);
    route.error = text;
    return route;
  };
  if (!from.allFinite() || !to.allFinite()) {
    route.error = "the start or the destination is not a position (NaN or infinite)";
    return route;
  }
  if (grid_.CellOf(from) < 0) return fail("start (%.2f, %.2f) is outside the plan", from.x(), from.y());
  if (grid_.CellOf(to) < 0)
    return fail("destination (%.2f, %.2f) is outside the plan", to.x(), to.y());
  const int start = Passable(grid_.CellOf(from)) ? grid_.CellOf(from) : Snap(from, -1);
  if (start < 0)
    return fail("start (%.2f, %.2f) has no free space around it (a wall, or the outside)",
                from.x(), from.y());
  int goal = grid_.CellOf(to);
  if (!Passable(goal) || component_[goal] != component_[start]) goal = Snap(to, component_[start]);
  if (goal < 0) {
    if (Snap(to, -1) < 0)
      return fail("destination (%.2f, %.2f) has no free space around it (a wall, or the outside)",
                  to.x(), to.y());
    std::snprintf(text, sizeof(text),
                  "no path: nothing at least %.2f m wide leads from (%.2f, %.2f) to (%.2f, %.2f)",
                  2 * options_.body_radius_m, from.x(), from.y(), to.x(), to.y());
    route.error = text;
    return route;
  }
  const std::vector<int> cells = GridAStar(grid_, passable_, start, goal);
  std::vector<Eigen::Vector2d> points;
  points.reserve(cells.size() + 2);
  const bool start_snapped = !Passable(grid_.CellOf(from));
  const bool goal_snapped = grid_.CellOf(to) != goal;
  if (start_snapped) points.push_back(from);  // where the wearer stands, then off the wall
  for (int c : cells) points.push_back(grid_.CellCentre(c));
  if (!start_snapped) points.front() = from;
  if (!goal_snapped) points.back() = to;
  // The first leg of a snapped start leaves the wall: not pulled, as it is not clear.
  std::vector<Eigen::Vector2d> tail(points.begin() + (start_snapped ? 1 : 0), points.end());
  route.path = PullString(tail, [this](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return LineOfSight(a, b);
  });
  if (start_snapped) {
    route.start_moved_m = (route.path.front() - from).norm();
    route.path.insert(route.path.begin(), from);
  }
  if (goal_snapped) route.goal_moved_m = (route.path.back() - to).norm();
  route.length_m = PolylineLength(route.path);
  return route;
}

}  // namespace floorpose
