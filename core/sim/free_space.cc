#include "core/sim/free_space.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iterator>
#include <limits>
#include <utility>

namespace floorpose::sim {
namespace {

// Grids larger than this get coarser cells (a 280 m square plan at 0.1 m): memory stays
// bounded whatever the plan.
constexpr double kMaxCells = 8e6;

// The largest 4-connected piece of the cells where mask is set (the first of equals), in
// ascending order.
std::vector<int> LargestComponent(const std::vector<uint8_t>& mask, int nx, int ny) {
  GridGeometry grid;
  grid.nx = nx, grid.ny = ny;
  std::vector<int> labels;
  const int count = LabelComponents(grid, mask, &labels);
  std::vector<size_t> sizes(count, 0);
  for (int label : labels)
    if (label >= 0) ++sizes[label];
  const int best =
      count == 0 ? -1
                 : static_cast<int>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
  std::vector<int> cells;
  for (int i = 0; i < nx * ny; ++i)
    if (labels[i] == best && best >= 0) cells.push_back(i);
  return cells;
}

}  // namespace

bool InsidePolygon(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p) {
  bool inside = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Eigen::Vector2d& a = poly[i];
    const Eigen::Vector2d& b = poly[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
      inside = !inside;
  }
  return inside;
}

double DistanceToPolygon(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p) {
  if (InsidePolygon(poly, p)) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    best = std::min(best, (ClosestPointOnSegment({poly[j], poly[i]}, p) - p).norm());
  return best;
}

FreeSpace::FreeSpace(const std::vector<Segment>& walls, const Eigen::Vector2d& min,
                     const Eigen::Vector2d& max, const FreeSpaceOptions& options)
    : options_(options) {
  const Eigen::Vector2d extent = (max - min).array() + 2.0 * options_.margin_m;
  if (!(extent.x() > 0) || !(extent.y() > 0) || walls.empty()) {
    region_ = "no walls";
    return;
  }
  options_.cell_m = std::max(options_.cell_m, std::sqrt(extent.x() * extent.y() / kMaxCells));
  origin_ = min.array() - options_.margin_m;
  nx_ = static_cast<int>(std::ceil(extent.x() / options_.cell_m)) + 1;
  ny_ = static_cast<int>(std::ceil(extent.y() / options_.cell_m)) + 1;
  const int n = nx_ * ny_;
  clearance_ = Clearance(BlockedCells(walls));
  std::vector<uint8_t> free(n, 0);
  for (int i = 0; i < n; ++i) free[i] = clearance_[i] >= options_.body_radius_m;
  ChooseRegion(free, IndoorCells(free), min, max);
}

std::vector<uint8_t> FreeSpace::BlockedCells(const std::vector<Segment>& walls) const {
  const double c = options_.cell_m;
  // Walls: every cell a wall passes through (sampled at half a cell).
  std::vector<uint8_t> blocked(static_cast<size_t>(nx_) * ny_, 0);
  for (const Segment& s : walls) {
    const int steps = std::max(1, static_cast<int>(std::ceil(s.Length() / (0.5 * c))));
    for (int i = 0; i <= steps; ++i) {
      const int cell = CellOf(s.a + (s.b - s.a) * (static_cast<double>(i) / steps));
      if (cell >= 0) blocked[cell] = 1;
    }
  }

  return blocked;
}

std::vector<float> FreeSpace::Clearance(const std::vector<uint8_t>& blocked) const {
  const int n = nx_ * ny_;
  // Clearance: the 3-4 chamfer distance transform (Borgefors 1986), two passes. It
  // underestimates diagonal distances by at most 6%, which errs on the safe side.
  std::vector<float> d(n, std::numeric_limits<float>::max() / 2);
  for (int i = 0; i < n; ++i)
    if (blocked[i]) d[i] = 0;
  auto relax = [&](int i, int x, int y, float w) {
    if (InGrid(x, y)) d[i] = std::min(d[i], d[y * nx_ + x] + w);
  };
  for (int y = 0; y < ny_; ++y)
    for (int x = 0; x < nx_; ++x) {
      const int i = y * nx_ + x;
      relax(i, x - 1, y, 3), relax(i, x, y - 1, 3), relax(i, x - 1, y - 1, 4),
          relax(i, x + 1, y - 1, 4);
    }
  for (int y = ny_ - 1; y >= 0; --y)
    for (int x = nx_ - 1; x >= 0; --x) {
      const int i = y * nx_ + x;
      relax(i, x + 1, y, 3), relax(i, x, y + 1, 3), relax(i, x + 1, y + 1, 4),
          relax(i, x - 1, y + 1, 4);
    }
  std::vector<float> clearance(n);
  for (int i = 0; i < n; ++i) clearance[i] = static_cast<float>(d[i] * options_.cell_m / 3.0);
  return clearance;
}

std::vector<uint8_t> FreeSpace::IndoorCells(const std::vector<uint8_t>& free) const {
  const int n = nx_ * ny_;
  // Indoors, decided per block of 6x6 cells from its walkable cell nearest the block's
  // centre. Rays march through the grown walls one cell at a time, so they cannot slip
  // through a wall; they do pass through doors, and then meet the next room's walls.
  constexpr int kBlock = 6;
  std::vector<uint8_t> indoor(n, 0);
  for (int by = 0; by < ny_; by += kBlock)
    for (int bx = 0; bx < nx_; bx += kBlock) {
      int probe = -1;
      double probe_d = 1e9;
      for (int y = by; y < std::min(by + kBlock, ny_); ++y)
        for (int x = bx; x < std::min(bx + kBlock, nx_); ++x) {
          const double dd = std::hypot(x - bx - 0.5 * (kBlock - 1), y - by - 0.5 * (kBlock - 1));
          if (free[y * nx_ + x] && dd < probe_d) probe = y * nx_ + x, probe_d = dd;
        }
      if (probe < 0) continue;
      int escaped = 0;
      for (int r = 0; r < options_.indoor_rays && escaped <= options_.max_escaping_rays; ++r) {
        const double a = 2.0 * M_PI * r / options_.indoor_rays;
        const double sx = std::cos(a), sy = std::sin(a);  // one cell a step, in cells
        double fx = probe % nx_ + 0.5, fy = probe / nx_ + 0.5;
        while (true) {
          fx += sx, fy += sy;
          if (!(fx >= 0 && fy >= 0 && fx < nx_ && fy < ny_)) {
            ++escaped;
            break;
          }
          if (!free[static_cast<int>(fy) * nx_ + static_cast<int>(fx)]) break;
        }
      }
      if (escaped > options_.max_escaping_rays) continue;
      for (int y = by; y < std::min(by + kBlock, ny_); ++y)
        for (int x = bx; x < std::min(bx + kBlock, nx_); ++x) indoor[y * nx_ + x] = 1;
    }

  return indoor;
}

void FreeSpace::ChooseRegion(const std::vector<uint8_t>& free, const std::vector<uint8_t>& indoor,
                             const Eigen::Vector2d& min, const Eigen::Vector2d& max) {
  const int n = nx_ * ny_;
  std::vector<uint8_t> mask(n, 0);
  for (int i = 0; i < n; ++i) mask[i] = free[i] && indoor[i];
  std::vector<int> enclosed = LargestComponent(mask, nx_, ny_);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d p = CellCentre(i);
    mask[i] = free[i] && (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
  std::vector<int> boxed = LargestComponent(mask, nx_, ny_);
  char text[200];
  if (static_cast<double>(enclosed.size()) >=
      options_.min_indoor_share * static_cast<double>(boxed.size())) {
    cells_ = std::move(enclosed);
    std::snprintf(text, sizeof(text), "the largest enclosed free region (%.0f m2)",
                  walkable_area_m2());
  } else {
    cells_ = std::move(boxed);
    std::snprintf(text, sizeof(text),
                  "the plan has no closed outline: the largest free region inside its "
                  "bounding box (%.0f m2)",
                  walkable_area_m2());
  }
  region_ = text;
  walkable_.assign(n, 0);
  for (int i : cells_) walkable_[i] = 1;
}

double FreeSpace::walkable_area_m2() const {
  return static_cast<double>(cells_.size()) * options_.cell_m * options_.cell_m;
}

Eigen::Vector2d FreeSpace::CellCentre(int cell) const {
  return origin_ + options_.cell_m * Eigen::Vector2d(cell % nx_ + 0.5, cell / nx_ + 0.5);
}

int FreeSpace::CellOf(const Eigen::Vector2d& p) const {
  const double fx = std::floor((p.x() - origin_.x()) / options_.cell_m);
  const double fy = std::floor((p.y() - origin_.y()) / options_.cell_m);
  if (!(fx >= 0 && fy >= 0 && fx < nx_ && fy < ny_)) return -1;
  return static_cast<int>(fy) * nx_ + static_cast<int>(fx);
}

bool FreeSpace::Walkable(const Eigen::Vector2d& p) const {
  const int cell = CellOf(p);
  return cell >= 0 && walkable_[cell];
}

double FreeSpace::Clearance(const Eigen::Vector2d& p) const {
  const int cell = CellOf(p);
  return cell >= 0 ? clearance_[cell] : 0.0;
}

int FreeSpace::MostOpenCell() const {
  int best = -1;
  for (int cell : cells_)
    if (best < 0 || clearance_[cell] > clearance_[best]) best = cell;
  return best;
}

size_t FreeSpace::Reach(int seed, const std::vector<uint8_t>& mask, std::vector<int>* out) const {
  std::vector<uint8_t> seen(mask.size(), 0);
  std::vector<int> queue{seed};
  seen[seed] = 1;
  size_t count = 0;
  while (!queue.empty()) {
    const int c = queue.back();
    queue.pop_back();
    ++count;
    if (out) out->push_back(c);
    const int x = c % nx_, y = c / nx_;
    const int next[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
    for (const auto& [qx, qy] : next) {
      if (!InGrid(qx, qy)) continue;
      const int q = qy * nx_ + qx;
      if (mask[q] && !seen[q]) {
        seen[q] = 1;
        queue.push_back(q);
      }
    }
  }
  if (out) std::sort(out->begin(), out->end());
  return count;
}

bool FreeSpace::BlockIfConnected(const std::vector<Eigen::Vector2d>& footprint) {
  if (footprint.size() < 3 || cells_.empty()) return false;
  Eigen::Vector2d lo = footprint[0], hi = footprint[0];
  for (const Eigen::Vector2d& p : footprint) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double r = options_.body_radius_m;
  const double c = options_.cell_m;
  const int x0 = std::max(0, static_cast<int>(std::floor((lo.x() - r - origin_.x()) / c)));
  const int y0 = std::max(0, static_cast<int>(std::floor((lo.y() - r - origin_.y()) / c)));
  const int x1 = std::min(nx_ - 1, static_cast<int>(std::floor((hi.x() + r - origin_.x()) / c)));
  const int y1 = std::min(ny_ - 1, static_cast<int>(std::floor((hi.y() + r - origin_.y()) / c)));
  std::vector<int> covered;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const int cell = y * nx_ + x;
      if (walkable_[cell] && DistanceToPolygon(footprint, CellCentre(cell)) <= r)
        covered.push_back(cell);
    }
  if (covered.empty()) return true;
  if (covered.size() >= cells_.size()) return false;
  for (int cell : covered) walkable_[cell] = 0;
  // Strictly connected: not even a pocket behind the object may be cut off, so that every
  // walkable cell stays reachable from every other. It is enough that the cells around the
  // object still reach each other: every path through the object can go round it then.
  // Usually they do nearby, so look in a window around the object first and flood the
  // whole region only when that fails.
  std::vector<int> ring;
  for (int cell : covered) {
    const int x = cell % nx_, y = cell / nx_;
    const int next[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
    for (const auto& [qx, qy] : next)
      if (InGrid(qx, qy) && walkable_[qy * nx_ + qx]) ring.push_back(qy * nx_ + qx);
  }
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  bool connected = ring.empty() || LocallyConnected(ring, x0 - 20, y0 - 20, x1 + 20, y1 + 20);
  if (!connected && !ring.empty())
    connected = Reach(ring[0], walkable_, nullptr) == cells_.size() - covered.size();
  if (!connected) {
    for (int cell : covered) walkable_[cell] = 1;
    return false;
  }
  std::vector<int> kept;
  kept.reserve(cells_.size() - covered.size());
  std::set_difference(cells_.begin(), cells_.end(), covered.begin(), covered.end(),
                      std::back_inserter(kept));
  cells_ = std::move(kept);
  return true;
}

bool FreeSpace::LocallyConnected(const std::vector<int>& ring, int x0, int y0, int x1,
                                 int y1) const {
  x0 = std::max(x0, 0), y0 = std::max(y0, 0);
  x1 = std::min(x1, nx_ - 1), y1 = std::min(y1, ny_ - 1);
  const int w = x1 - x0 + 1;
  std::vector<uint8_t> seen(static_cast<size_t>(w) * (y1 - y0 + 1), 0);
  auto local = [&](int cell) { return (cell / nx_ - y0) * w + cell % nx_ - x0; };
  std::vector<int> queue{ring[0]};
  seen[local(ring[0])] = 1;
  while (!queue.empty()) {
    const int c = queue.back();
    queue.pop_back();
    const int x = c % nx_, y = c / nx_;
    const int next[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
    for (const auto& [qx, qy] : next) {
      if (qx < x0 || qy < y0 || qx > x1 || qy > y1) continue;
      const int q = qy * nx_ + qx;
      if (walkable_[q] && !seen[local(q)]) {
        seen[local(q)] = 1;
        queue.push_back(q);
      }
    }
  }
  for (int cell : ring)
    if (!seen[local(cell)]) return false;
  return true;
}

void FreeSpace::RestrictTo(int cell, double min_clearance_m) {
  if (cell < 0 || cell >= nx_ * ny_) return;
  std::vector<uint8_t> mask(walkable_.size(), 0);
  for (int i : cells_) mask[i] = clearance_[i] >= min_clearance_m;
  if (!mask[cell]) return;
  std::vector<int> kept;
  Reach(cell, mask, &kept);
  walkable_.assign(walkable_.size(), 0);
  for (int i : kept) walkable_[i] = 1;
  cells_ = std::move(kept);
}

bool FreeSpace::LineOfSight(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  // Samples at half a cell: a walkable cell centre is at least a body radius minus the
  // chamfer error from every wall, far more than the gap between two samples.
  const int steps =
      std::max(1, static_cast<int>(std::ceil((b - a).norm() / (0.5 * options_.cell_m))));
  for (int i = 0; i <= steps; ++i)
    if (!Walkable(a + (b - a) * (static_cast<double>(i) / steps))) return false;
  return true;
}

std::vector<Eigen::Vector2d> FreeSpace::Path(const Eigen::Vector2d& from,
                                             const Eigen::Vector2d& to) const {
  const int start = CellOf(from), goal = CellOf(to);
  if (start < 0 || goal < 0 || !walkable_[start] || !walkable_[goal]) return {};
  const GridGeometry grid{origin_, options_.cell_m, nx_, ny_};
  const std::vector<int> steps = GridAStar(grid, walkable_, start, goal, [&](int cell) {
    const double near_wall = std::max(0.0, 1.0 - clearance_[cell] / options_.centre_clearance_m);
    return 1.0 + options_.centre_weight * near_wall;
  });
  if (steps.empty()) return {};
  std::vector<Eigen::Vector2d> cells;
  cells.reserve(steps.size());
  for (int c : steps) cells.push_back(CellCentre(c));
  cells.front() = from;
  cells.back() = to;
  return PullString(cells, [this](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return LineOfSight(a, b);
  });
}

}  // namespace floorpose::sim
