#include "core/route_planner.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <queue>
#include <utility>

namespace floorpose {
namespace {

// Whether a cell (-1: none) is passable in `passable`.
auto PassableIn(const std::vector<uint8_t>& passable) {
  return [&passable](int cell) { return cell >= 0 && passable[cell]; };
}

}  // namespace

RoutePlanner::RoutePlanner(const FloorPlan& plan, const RouteOptions& options) : options_(options) {
  for (const PlanLine& o : plan.openings)
    if (o.kind == LineKind::kExit) exits_.push_back(0.5 * (o.segment.a + o.segment.b));
  if (exits_.empty())  // an upper floor: the way out is down the stairs
    for (size_t i = 0; i < plan.segments.size(); ++i)
      if (plan.KindOf(i) == LineKind::kStairs)
        exits_.push_back(0.5 * (plan.segments[i].a + plan.segments[i].b));
  // No margin: a route stays within the plan's bounds.
  grid_ = GridGeometry::Cover(plan.min, plan.max, options_.cell_m, 0.0, options_.max_cells);
  const double keep = options_.body_radius_m + grid_.cell_m * M_SQRT1_2;
  passable_ = CellsNearWalls(grid_, plan.segments, keep);
  for (size_t i = 0; i < passable_.size(); ++i) {
    const Eigen::Vector2d c = grid_.CellCentre(static_cast<int>(i));
    const bool inside =
        (c.array() >= plan.min.array()).all() && (c.array() <= plan.max.array()).all();
    passable_[i] = !passable_[i] && inside;
  }
  LabelComponents(grid_, passable_, &component_);
  // The search buffers now, with their pages, rather than in the first route.
  scratch_.stamp.assign(grid_.size(), 0);
  scratch_.g.assign(grid_.size(), 0.0);
  scratch_.parent.assign(grid_.size(), -1);
  scratch_.closed.assign(grid_.size(), 0);
  coarse_.origin = grid_.origin;
  coarse_.cell_m = grid_.cell_m * kCoarse;
  coarse_.nx = (grid_.nx + kCoarse - 1) / kCoarse;
  coarse_.ny = (grid_.ny + kCoarse - 1) / kCoarse;
  coarse_open_.assign(coarse_.size(), 0);
  for (int i = 0; i < static_cast<int>(grid_.size()); ++i)
    if (passable_[i])
      coarse_open_[(i / grid_.nx / kCoarse) * coarse_.nx + i % grid_.nx / kCoarse] = 1;
}

std::vector<float> RoutePlanner::CoarseDistances(int goal, int start) const {
  auto coarse_cell = [this](int cell) {
    return (cell / grid_.nx / kCoarse) * coarse_.nx + cell % grid_.nx / kCoarse;
  };
  const int g = coarse_cell(goal), s = coarse_cell(start);
  float stop = std::numeric_limits<float>::infinity();
  std::vector<float> dist(coarse_.size(), std::numeric_limits<float>::infinity());
  using Entry = std::pair<float, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  dist[g] = 0;
  open.push({0.0f, g});
  while (!open.empty()) {
    const auto [d, c] = open.top();
    open.pop();
    if (d > dist[c]) continue;
    if (c == s) stop = 1.25f * d + 4.0f;  // A* rarely strays farther from the goal
    if (d > stop) {
      for (float& far : dist) far = std::min(far, d);  // every unsettled cell is this far
      break;
    }
    const int x = c % coarse_.nx, y = c / coarse_.nx;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || !coarse_.InGrid(x + dx, y + dy)) continue;
        const int q = (y + dy) * coarse_.nx + x + dx;
        const float nd = d + (dx != 0 && dy != 0 ? static_cast<float>(M_SQRT2) : 1.0f);
        if (coarse_open_[q] && nd < dist[q]) {
          dist[q] = nd;
          open.push({nd, q});
        }
      }
  }
  return dist;
}

bool RoutePlanner::LineOfSight(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  return WalkSegmentCells(grid_, a, b, [this](int cell) { return Passable(cell); });
}

std::vector<uint8_t> RoutePlanner::WithKeepOuts(const Eigen::Vector2d& from,
                                                const std::vector<KeepOut>& keep_out) const {
  std::vector<uint8_t> passable = passable_;
  const double margin = options_.body_radius_m + grid_.cell_m * M_SQRT1_2;
  for (const KeepOut& k : keep_out) {
    if (!k.centre.allFinite() || !(k.radius_m >= 0) || (from - k.centre).norm() <= k.radius_m)
      continue;
    const double reach = k.radius_m + margin;
    const int x0 =
        static_cast<int>(std::floor((k.centre.x() - reach - grid_.origin.x()) / grid_.cell_m));
    const int y0 =
        static_cast<int>(std::floor((k.centre.y() - reach - grid_.origin.y()) / grid_.cell_m));
    const int n = static_cast<int>(std::ceil(2 * reach / grid_.cell_m)) + 1;
    for (int y = std::max(0, y0); y < std::min(grid_.ny, y0 + n); ++y)
      for (int x = std::max(0, x0); x < std::min(grid_.nx, x0 + n); ++x) {
        const int cell = y * grid_.nx + x;
        if ((grid_.CellCentre(cell) - k.centre).norm() <= reach) passable[cell] = 0;
      }
  }
  return passable;
}

int RoutePlanner::Snap(const std::vector<uint8_t>& passable, const Eigen::Vector2d& p,
                       int component) const {
  const int reach = static_cast<int>(std::ceil(options_.snap_m / grid_.cell_m));
  const Eigen::Vector2d f = (p - grid_.origin) / grid_.cell_m;
  const int cx = static_cast<int>(std::floor(f.x())), cy = static_cast<int>(std::floor(f.y()));
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (int y = cy - reach; y <= cy + reach; ++y)
    for (int x = cx - reach; x <= cx + reach; ++x) {
      if (!grid_.InGrid(x, y)) continue;
      const int cell = y * grid_.nx + x;
      if (!passable[cell] || (component >= 0 && component_[cell] != component)) continue;
      const double d = (grid_.CellCentre(cell) - p).norm();
      if (d <= options_.snap_m && d < best_d) best = cell, best_d = d;
    }
  return best;
}

std::string RoutePlanner::Refusal(const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                                  const std::vector<KeepOut>& keep_out) const {
  char text[256];
  auto say = [&](const char* format, double a, double b) {
    std::snprintf(text, sizeof(text), format, a, b);
    return std::string(text);
  };
  if (!from.allFinite() || !to.allFinite())
    return "the start or the destination is not a position (NaN or infinite)";
  if (grid_.CellOf(from) < 0)
    return say("start (%.2f, %.2f) is outside the plan", from.x(), from.y());
  if (grid_.CellOf(to) < 0)
    return say("destination (%.2f, %.2f) is outside the plan", to.x(), to.y());
  for (const KeepOut& k : keep_out)
    if ((to - k.centre).norm() <= k.radius_m && (from - k.centre).norm() > k.radius_m)
      return say("destination (%.2f, %.2f) is in a blocked area", to.x(), to.y());
  return {};
}

Route RoutePlanner::Plan(const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                         const std::vector<KeepOut>& keep_out) const {
  Route route;
  route.error = Refusal(from, to, keep_out);
  if (!route.ok()) return route;
  return keep_out.empty() ? Search(passable_, from, to)
                          : Search(WithKeepOuts(from, keep_out), from, to);
}

Route RoutePlanner::Search(const std::vector<uint8_t>& passable, const Eigen::Vector2d& from,
                           const Eigen::Vector2d& to) const {
  Route route;
  char text[256];
  auto fail = [&](const char* format, double a, double b) {
    std::snprintf(text, sizeof(text), format, a, b);
    route.error = text;
    return route;
  };
  const auto open = PassableIn(passable);
  const int start = open(grid_.CellOf(from)) ? grid_.CellOf(from) : Snap(passable, from, -1);
  if (start < 0)
    return fail("start (%.2f, %.2f) has no free space around it (a wall, or the outside)", from.x(),
                from.y());
  int goal = grid_.CellOf(to);
  if (!open(goal) || component_[goal] != component_[start])
    goal = Snap(passable, to, component_[start]);
  if (goal < 0) {
    if (Snap(passable, to, -1) < 0)
      return fail("destination (%.2f, %.2f) has no free space around it (a wall, or the outside)",
                  to.x(), to.y());
    std::snprintf(text, sizeof(text),
                  "no path: nothing at least %.2f m wide leads from (%.2f, %.2f) to (%.2f, %.2f)",
                  2 * options_.body_radius_m, from.x(), from.y(), to.x(), to.y());
    route.error = text;
    return route;
  }
  const std::lock_guard<std::mutex> lock(search_mutex_);
  const std::vector<float> coarse = CoarseDistances(goal, start);
  const int gx = goal % grid_.nx, gy = goal / grid_.nx;
  const std::vector<int> cells = GridAStar(
      grid_, passable, start, goal, nullptr,
      [&](int cell) {
        const double dx = std::abs(cell % grid_.nx - gx), dy = std::abs(cell / grid_.nx - gy);
        const double octile = std::max(dx, dy) + (M_SQRT2 - 1.0) * std::min(dx, dy);
        const float d =
            coarse[(cell / grid_.nx / kCoarse) * coarse_.nx + cell % grid_.nx / kCoarse];
        // 0.1% over: of two cells with the same estimated total, the one nearer the goal
        // goes first, instead of every cell of an open room's plateau.
        return 1.001 * std::max(octile, (static_cast<double>(d) - 2 * M_SQRT2) * kCoarse);
      },
      &scratch_);
  if (cells.empty()) {
    std::snprintf(text, sizeof(text),
                  "no path: the blocked areas close every way from (%.2f, %.2f) to (%.2f, %.2f)",
                  from.x(), from.y(), to.x(), to.y());
    route.error = text;
    return route;
  }
  ShapePath(cells, passable, from, to, goal, &route);
  return route;
}

void RoutePlanner::ShapePath(const std::vector<int>& cells, const std::vector<uint8_t>& passable,
                             const Eigen::Vector2d& from, const Eigen::Vector2d& to, int goal,
                             Route* route) const {
  const auto open = PassableIn(passable);
  std::vector<Eigen::Vector2d> points;
  points.reserve(cells.size() + 2);
  const bool start_snapped = !open(grid_.CellOf(from));
  const bool goal_snapped = grid_.CellOf(to) != goal;
  if (start_snapped) points.push_back(from);  // where the wearer stands, then off the wall
  for (int c : cells) points.push_back(grid_.CellCentre(c));
  if (!start_snapped) points.front() = from;
  if (!goal_snapped) points.back() = to;
  // The first leg of a snapped start leaves the wall: not pulled, as it is not clear.
  std::vector<Eigen::Vector2d> tail(points.begin() + (start_snapped ? 1 : 0), points.end());
  auto sight = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return WalkSegmentCells(grid_, a, b, open);
  };
  route->path = PullString(tail, sight);
  DropCorners(&route->path, sight);
  if (start_snapped) {
    route->start_moved_m = (route->path.front() - from).norm();
    route->path.insert(route->path.begin(), from);
  }
  if (goal_snapped) route->goal_moved_m = (route->path.back() - to).norm();
  route->length_m = PolylineLength(route->path);
}

Route RoutePlanner::WayOut(const Eigen::Vector2d& from,
                           const std::vector<KeepOut>& keep_out) const {
  if (exits_.empty()) {
    Route none;
    none.error = "the plan marks no exit and no stairs";
    return none;
  }
  // The eight nearest as the crow flies; a route is at least that long, so the search
  // stops once the crow's distance passes the best route found.
  std::vector<Eigen::Vector2d> by_distance = exits_;
  std::sort(by_distance.begin(), by_distance.end(), [&](const auto& a, const auto& b) {
    return (a - from).squaredNorm() < (b - from).squaredNorm();
  });
  if (by_distance.size() > 8) by_distance.resize(8);
  // One grid with the keep-outs for every exit tried: they all start where the wearer is.
  const std::vector<uint8_t> blocked =
      keep_out.empty() ? std::vector<uint8_t>{} : WithKeepOuts(from, keep_out);
  Route best;
  for (const Eigen::Vector2d& exit : by_distance) {
    if (!best.path.empty() && (exit - from).norm() >= best.length_m) break;
    Route route;
    route.error = Refusal(from, exit, keep_out);
    if (route.ok()) route = Search(keep_out.empty() ? passable_ : blocked, from, exit);
    if (route.ok() && (best.path.empty() || route.length_m < best.length_m)) {
      best = std::move(route);
    } else if (!route.ok() && best.path.empty()) {
      best.error = "no route to an exit: " + route.error;
    }
  }
  return best;
}

Route RoutePlanner::Through(const Eigen::Vector2d& from, const std::vector<Eigen::Vector2d>& via,
                            const Eigen::Vector2d& to, const std::vector<KeepOut>& keep_out) const {
  // The grid with the keep-outs, made again only when a leg starts inside other ones than
  // the leg before (each leg leaves out those that hold its start, as Plan does).
  std::vector<uint8_t> blocked;
  std::vector<bool> left_out, leg_left_out(keep_out.size());
  auto grid_for = [&](const Eigen::Vector2d& start) -> const std::vector<uint8_t>& {
    if (keep_out.empty()) return passable_;
    for (size_t k = 0; k < keep_out.size(); ++k)
      leg_left_out[k] = (start - keep_out[k].centre).norm() <= keep_out[k].radius_m;
    if (blocked.empty() || leg_left_out != left_out) {
      blocked = WithKeepOuts(start, keep_out);
      left_out = leg_left_out;
    }
    return blocked;
  };
  Route route;
  route.path = {from};
  Eigen::Vector2d at = from;
  for (size_t i = 0; i <= via.size(); ++i) {
    const bool last = i == via.size();
    const Eigen::Vector2d& next = last ? to : via[i];
    Route leg;
    leg.error = Refusal(at, next, keep_out);
    if (leg.ok()) leg = Search(grid_for(at), at, next);
    if (!leg.ok()) {
      if (last) return leg;
      continue;  // passed over; the next waypoint is tried from here
    }
    route.path.insert(route.path.end(), leg.path.begin() + 1, leg.path.end());
    if (last) route.goal_moved_m = leg.goal_moved_m;
    at = route.path.back();
  }
  const std::vector<uint8_t>& passable = grid_for(from);
  const auto open = PassableIn(passable);
  DropCorners(&route.path, [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return WalkSegmentCells(grid_, a, b, open);
  });
  route.length_m = PolylineLength(route.path);
  return route;
}

}  // namespace floorpose
