#include "core/explored_map.h"

#include <algorithm>
#include <cmath>

namespace floorpose {

ExploredMap::ExploredMap(const FloorPlan& plan, std::shared_ptr<const RoomMap> rooms,
                         const ExploredOptions& options)
    : options_(options),
      grid_(GridGeometry::Cover(plan.min, plan.max, options.cell_m, 1.0, options.max_cells)),
      rooms_(std::move(rooms)),
      log_odds_(grid_.size(), 0.0f) {}

void ExploredMap::Add(int cell, float value) {
  float& l = log_odds_[cell];
  l = std::clamp(l + value, -options_.clamp, options_.clamp);
}

void ExploredMap::AddWalls(const Eigen::Vector2d& origin,
                           const std::vector<Eigen::Vector2d>& points) {
  if (!origin.allFinite()) return;
  const double max2 = options_.max_ray_m * options_.max_ray_m;
  bool changed = false;
  for (const Eigen::Vector2d& p : points) {
    if (!p.allFinite() || (p - origin).squaredNorm() > max2) continue;
    const int end = grid_.CellOf(p);
    if (end < 0) continue;
    // Bresenham from the origin's cell to the point's: free up to it, a wall at it.
    const int x1 = end % grid_.nx, y1 = end / grid_.nx;
    const Eigen::Vector2d f = (origin - grid_.origin) / grid_.cell_m;
    int x = static_cast<int>(std::floor(f.x())), y = static_cast<int>(std::floor(f.y()));
    const int dx = std::abs(x1 - x), dy = -std::abs(y1 - y);
    const int sx = x < x1 ? 1 : -1, sy = y < y1 ? 1 : -1;
    int err = dx + dy;
    while (x != x1 || y != y1) {
      if (grid_.InGrid(x, y)) Add(y * grid_.nx + x, options_.miss);
      const int e2 = 2 * err;
      if (e2 >= dy) err += dy, x += sx;
      if (e2 <= dx) err += dx, y += sy;
    }
    Add(end, options_.hit);
    changed = true;
  }
  if (changed) ++revision_;
}

void ExploredMap::AddVisit(const Eigen::Vector2d& position) {
  if (!position.allFinite() || grid_.CellOf(position) < 0) return;
  const double r = options_.body_radius_m;
  const int reach = static_cast<int>(std::ceil(r / grid_.cell_m));
  const int centre = grid_.CellOf(position);
  const int cx = centre % grid_.nx, cy = centre / grid_.nx;
  for (int y = cy - reach; y <= cy + reach; ++y)
    for (int x = cx - reach; x <= cx + reach; ++x) {
      if (!grid_.InGrid(x, y)) continue;
      const int cell = y * grid_.nx + x;
      if ((grid_.CellCentre(cell) - position).norm() <= r) Add(cell, options_.miss);
    }
  if (rooms_) {
    const int room = rooms_->RoomAt(position);
    if (room >= 0) ++visits_[room];
  }
  ++revision_;
}

bool ExploredMap::Merge(const ExploredMap& other) {
  if (!(other.grid_ == grid_)) return false;
  for (size_t i = 0; i < log_odds_.size(); ++i) Add(static_cast<int>(i), other.log_odds_[i]);
  for (const auto& [room, poses] : other.visits_) visits_[room] += poses;
  ++revision_;
  return true;
}

bool ExploredMap::SetLogOdds(std::vector<float> log_odds) {
  if (log_odds.size() != log_odds_.size()) return false;
  log_odds_ = std::move(log_odds);
  for (float& l : log_odds_)
    l = std::isfinite(l) ? std::clamp(l, -options_.clamp, options_.clamp) : 0.0f;
  ++revision_;
  return true;
}

float ExploredMap::LogOdds(const Eigen::Vector2d& p) const {
  const int cell = grid_.CellOf(p);
  return cell < 0 ? 0.0f : log_odds_[cell];
}

std::vector<int> ExploredMap::VisitedRooms() const {
  std::vector<int> rooms;
  for (const auto& [room, poses] : visits_)
    if (poses >= options_.min_visit_poses) rooms.push_back(room);
  return rooms;
}

}  // namespace floorpose
