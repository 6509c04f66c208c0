#include "core/distance_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace floorpose {

DistanceGrid::DistanceGrid(const std::vector<Segment>& walls, const Eigen::Vector2d& min,
                           const Eigen::Vector2d& max, double cell_m, double near_m,
                           double max_cells)
    : grid_(GridGeometry::Cover(min, max, cell_m, near_m + cell_m, max_cells)),
      near_m_(near_m),
      d2_(grid_.size(), kFar) {
  walls_min_ = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  walls_max_ = -walls_min_;
  for (const Segment& s : walls) {
    walls_min_ = walls_min_.cwiseMin(s.a.cwiseMin(s.b));
    walls_max_ = walls_max_.cwiseMax(s.a.cwiseMax(s.b));
  }
  const double c = grid_.cell_m, near2 = near_m * near_m;
  const double scale = (kFar - 1) / near2;
  // Every segment stamps the centres within near_m of it with the smaller squared distance,
  // row by row: in a row, only where the segment comes within near_m of it (a long
  // diagonal wall visits a band about itself, not its bounding box).
  auto row_of = [&](double y) { return (y - grid_.origin.y()) / c - 0.5; };
  auto column_of = [&](double x) { return (x - grid_.origin.x()) / c - 0.5; };
  for (const Segment& s : walls) {
    const Eigen::Vector2d d = s.b - s.a;
    const int y0 =
        std::max(0, static_cast<int>(std::floor(row_of(std::min(s.a.y(), s.b.y()) - near_m))));
    const int y1 = std::min(
        grid_.ny - 1, static_cast<int>(std::ceil(row_of(std::max(s.a.y(), s.b.y()) + near_m))));
    for (int y = y0; y <= y1; ++y) {
      const double yc = grid_.origin.y() + (y + 0.5) * c;
      // The part of the segment within near_m of the row's line, in x, grown by near_m.
      double t0 = 0, t1 = 1;
      if (d.y() != 0) {
        t0 = (yc - near_m - s.a.y()) / d.y();
        t1 = (yc + near_m - s.a.y()) / d.y();
        if (t0 > t1) std::swap(t0, t1);
        t0 = std::max(t0, 0.0);
        t1 = std::min(t1, 1.0);
        if (t0 > t1) continue;
      } else if (std::abs(yc - s.a.y()) > near_m) {
        continue;
      }
      const double xa = s.a.x() + t0 * d.x(), xb = s.a.x() + t1 * d.x();
      const int x0 =
          std::max(0, static_cast<int>(std::floor(column_of(std::min(xa, xb) - near_m))));
      const int x1 =
          std::min(grid_.nx - 1, static_cast<int>(std::ceil(column_of(std::max(xa, xb) + near_m))));
      for (int x = x0; x <= x1; ++x) {
        const int cell = y * grid_.nx + x;
        const Eigen::Vector2d p = grid_.CellCentre(cell);
        const double d2 = (ClosestPointOnSegment(s, p) - p).squaredNorm();
        if (d2 > near2) continue;
        const auto q = static_cast<uint16_t>(std::lround(d2 * scale));
        d2_[cell] = std::min(d2_[cell], q);
      }
    }
  }
}

std::optional<double> DistanceGrid::Near(const Eigen::Vector2d& p, double* at_least) const {
  if (at_least) *at_least = 0;
  if (d2_.empty()) return std::nullopt;
  const double fx = (p.x() - grid_.origin.x()) / grid_.cell_m - 0.5;
  const double fy = (p.y() - grid_.origin.y()) / grid_.cell_m - 0.5;
  if (!(fx >= 0 && fy >= 0 && fx < grid_.nx - 1 && fy < grid_.ny - 1)) {
    if (at_least) *at_least = BoxBound(p);
    return std::nullopt;
  }
  const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
  const size_t i = static_cast<size_t>(iy) * grid_.nx + ix;
  const uint16_t a = d2_[i], b = d2_[i + 1], c = d2_[i + grid_.nx], d = d2_[i + grid_.nx + 1];
  const double tx = fx - ix, ty = fy - iy;
  if (a == kFar || b == kFar || c == kFar || d == kFar) {
    if (at_least) {
      const uint16_t corners[4] = {a, b, c, d};
      *at_least = FarCentreBound(corners, tx, ty);
    }
    return std::nullopt;
  }
  const double q = (1 - ty) * ((1 - tx) * a + tx * b) + ty * ((1 - tx) * c + tx * d);
  return near_m_ * std::sqrt(q / (kFar - 1));
}

// Covers the rounding of the bounds, far below any distance that matters.
constexpr double kSlackM = 1e-9;

double DistanceGrid::BoxBound(const Eigen::Vector2d& p) const {
  if (!p.allFinite()) return 0;
  // No wall lies outside the walls' box.
  return std::max(0.0, std::sqrt(SquaredDistanceToBox(p, walls_min_, walls_max_)) - kSlackM);
}

double DistanceGrid::FarCentreBound(const uint16_t corners[4], double tx, double ty) const {
  // A centre marked far is more than near_m from every wall, and p is its offset from it
  // nearer at most.
  const double offsets[4][2] = {{tx, ty}, {1 - tx, ty}, {tx, 1 - ty}, {1 - tx, 1 - ty}};
  double nearest2 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 4; ++k)
    if (corners[k] == kFar)
      nearest2 = std::min(nearest2, offsets[k][0] * offsets[k][0] + offsets[k][1] * offsets[k][1]);
  return std::max(0.0, near_m_ - std::sqrt(nearest2) * grid_.cell_m - kSlackM);
}

}  // namespace floorpose
