#include "core/grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <utility>

namespace floorpose {

GridGeometry GridGeometry::Cover(const Eigen::Vector2d& min, const Eigen::Vector2d& max,
                                 double cell_m, double margin_m, double max_cells) {
  GridGeometry g;
  const Eigen::Vector2d extent = (max - min).array().max(0.0) + 2.0 * margin_m;
  g.cell_m = std::max(cell_m, std::sqrt(extent.x() * extent.y() / max_cells));
  g.origin = min.array() - margin_m;
  g.nx = static_cast<int>(std::ceil(extent.x() / g.cell_m)) + 1;
  g.ny = static_cast<int>(std::ceil(extent.y() / g.cell_m)) + 1;
  return g;
}

int GridGeometry::CellOf(const Eigen::Vector2d& p) const {
  const double fx = std::floor((p.x() - origin.x()) / cell_m);
  const double fy = std::floor((p.y() - origin.y()) / cell_m);
  if (!(fx >= 0 && fy >= 0 && fx < nx && fy < ny)) return -1;
  return static_cast<int>(fy) * nx + static_cast<int>(fx);
}

std::vector<uint8_t> CellsNearWalls(const GridGeometry& grid, const std::vector<Segment>& walls,
                                    double radius_m) {
  std::vector<uint8_t> near(grid.size(), 0);
  const double c = grid.cell_m;
  for (const Segment& s : walls) {
    const Eigen::Vector2d lo = s.a.cwiseMin(s.b).array() - radius_m - grid.origin.array();
    const Eigen::Vector2d hi = s.a.cwiseMax(s.b).array() + radius_m - grid.origin.array();
    const int x0 = std::max(0, static_cast<int>(std::floor(lo.x() / c)));
    const int y0 = std::max(0, static_cast<int>(std::floor(lo.y() / c)));
    const int x1 = std::min(grid.nx - 1, static_cast<int>(std::floor(hi.x() / c)));
    const int y1 = std::min(grid.ny - 1, static_cast<int>(std::floor(hi.y() / c)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const int cell = y * grid.nx + x;
        if (near[cell]) continue;
        const Eigen::Vector2d p = grid.CellCentre(cell);
        if ((ClosestPointOnSegment(s, p) - p).squaredNorm() < radius_m * radius_m) near[cell] = 1;
      }
  }
  return near;
}

int LabelComponents(const GridGeometry& grid, const std::vector<uint8_t>& mask,
                    std::vector<int>* labels) {
  labels->assign(grid.size(), -1);
  int count = 0;
  std::vector<int> stack;
  for (int start = 0; start < static_cast<int>(grid.size()); ++start) {
    if (!mask[start] || (*labels)[start] >= 0) continue;
    (*labels)[start] = count;
    stack.assign(1, start);
    while (!stack.empty()) {
      const int c = stack.back();
      stack.pop_back();
      const int x = c % grid.nx, y = c / grid.nx;
      const int next[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
      for (const auto& [qx, qy] : next) {
        if (!grid.InGrid(qx, qy)) continue;
        const int q = qy * grid.nx + qx;
        if (mask[q] && (*labels)[q] < 0) {
          (*labels)[q] = count;
          stack.push_back(q);
        }
      }
    }
    ++count;
  }
  return count;
}

std::vector<int> GridAStar(const GridGeometry& grid, const std::vector<uint8_t>& passable,
                           int start, int goal, const std::function<double(int)>& step_weight,
                           const std::function<double(int)>& heuristic,
                           GridSearchScratch* scratch) {
  const int n = static_cast<int>(grid.size());
  if (start < 0 || goal < 0 || start >= n || goal >= n || !passable[start] || !passable[goal])
    return {};
  const int nx = grid.nx;
  const int gx = goal % nx, gy = goal / nx;
  auto h = [&](int cell) {  // octile distance in cells: admissible, weights are >= 1
    const double dx = std::abs(cell % nx - gx), dy = std::abs(cell / nx - gy);
    const double octile = std::max(dx, dy) + (M_SQRT2 - 1.0) * std::min(dx, dy);
    return heuristic ? std::max(octile, heuristic(cell)) : octile;
  };
  GridSearchScratch local;
  GridSearchScratch& s = scratch ? *scratch : local;
  s.Begin(grid.size());
  using Entry = std::pair<double, int>;  // (f, cell): ties break on the cell, deterministic
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  s.Touch(start);
  s.g[start] = 0;
  open.push({h(start), start});
  bool reached = false;
  while (!open.empty()) {
    const int c = open.top().second;
    open.pop();
    if (s.closed[c]) continue;
    s.closed[c] = 1;
    if (c == goal) {
      reached = true;
      break;
    }
    const int x = c % nx, y = c / nx;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || !grid.InGrid(x + dx, y + dy)) continue;
        const int q = (y + dy) * nx + x + dx;
        if (!passable[q]) continue;
        s.Touch(q);
        if (s.closed[q]) continue;
        if (dx != 0 && dy != 0 && (!passable[y * nx + x + dx] || !passable[(y + dy) * nx + x]))
          continue;
        const double cost =
            (dx != 0 && dy != 0 ? M_SQRT2 : 1.0) * (step_weight ? step_weight(q) : 1.0);
        if (s.g[c] + cost < s.g[q]) {
          s.g[q] = s.g[c] + cost;
          s.parent[q] = c;
          open.push({s.g[q] + h(q), q});
        }
      }
  }
  if (!reached) return {};
  std::vector<int> cells;
  for (int c = goal; c >= 0; c = s.parent[c]) cells.push_back(c);
  std::reverse(cells.begin(), cells.end());
  return cells;
}

std::vector<Eigen::Vector2d> PullString(
    const std::vector<Eigen::Vector2d>& points,
    const std::function<bool(const Eigen::Vector2d&, const Eigen::Vector2d&)>& line_of_sight) {
  if (points.empty()) return {};
  std::vector<Eigen::Vector2d> path{points.front()};
  size_t i = 0;
  while (i + 1 < points.size()) {
    size_t j = i + 1;
    while (j + 1 < points.size() && line_of_sight(points[i], points[j + 1])) ++j;
    path.push_back(points[j]);
    i = j;
  }
  return path;
}

void DropCorners(
    std::vector<Eigen::Vector2d>* path,
    const std::function<bool(const Eigen::Vector2d&, const Eigen::Vector2d&)>& line_of_sight) {
  for (bool dropped = true; dropped;) {
    dropped = false;
    for (size_t i = 1; i + 1 < path->size();) {
      if (line_of_sight((*path)[i - 1], (*path)[i + 1])) {
        path->erase(path->begin() + static_cast<std::ptrdiff_t>(i));
        dropped = true;
      } else {
        ++i;
      }
    }
  }
}

bool WalkSegmentCells(const GridGeometry& grid, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                      const std::function<bool(int)>& visit) {
  const Eigen::Vector2d fa = (a - grid.origin) / grid.cell_m;
  const Eigen::Vector2d fb = (b - grid.origin) / grid.cell_m;
  if (!fa.allFinite() || !fb.allFinite()) return visit(-1);
  int x = static_cast<int>(std::floor(fa.x())), y = static_cast<int>(std::floor(fa.y()));
  const int xe = static_cast<int>(std::floor(fb.x())), ye = static_cast<int>(std::floor(fb.y()));
  auto cell = [&](int ix, int iy) { return grid.InGrid(ix, iy) ? iy * grid.nx + ix : -1; };
  if (!visit(cell(x, y))) return false;
  const double dx = fb.x() - fa.x(), dy = fb.y() - fa.y();
  const int sx = dx > 0 ? 1 : -1, sy = dy > 0 ? 1 : -1;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double tdx = dx != 0 ? 1.0 / std::abs(dx) : kInf;
  const double tdy = dy != 0 ? 1.0 / std::abs(dy) : kInf;
  double tx = dx != 0 ? (sx > 0 ? x + 1 - fa.x() : fa.x() - x) * tdx : kInf;
  double ty = dy != 0 ? (sy > 0 ? y + 1 - fa.y() : fa.y() - y) * tdy : kInf;
  for (int left = std::abs(xe - x) + std::abs(ye - y); left > 0;) {
    if (std::abs(tx - ty) < 1e-12 && left >= 2) {  // exactly through a corner
      if (!visit(cell(x + sx, y)) || !visit(cell(x, y + sy))) return false;
      x += sx, y += sy, tx += tdx, ty += tdy, left -= 2;
    } else if (tx < ty) {
      x += sx, tx += tdx, --left;
    } else {
      y += sy, ty += tdy, --left;
    }
    if (!visit(cell(x, y))) return false;
  }
  return true;
}

double PolylineLength(const std::vector<Eigen::Vector2d>& path) {
  double length = 0;
  for (size_t i = 1; i < path.size(); ++i) length += (path[i] - path[i - 1]).norm();
  return length;
}

}  // namespace floorpose
