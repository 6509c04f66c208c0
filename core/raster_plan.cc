#include "core/raster_plan.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace floorpose {

namespace {

// Why the raster cannot be read; empty when it can.
std::string RasterError(const OccupancyRaster& raster, const RasterPlanOptions& options) {
  if (raster.width <= 0 || raster.height <= 0 ||
      static_cast<size_t>(raster.width) * static_cast<size_t>(raster.height) > options.max_cells)
    return "raster plan: bad size " + std::to_string(raster.width) + " x " +
           std::to_string(raster.height) + " (at most " + std::to_string(options.max_cells) +
           " cells)";
  if (raster.occupied.size() != static_cast<size_t>(raster.width) * raster.height)
    return "raster plan: " + std::to_string(raster.occupied.size()) + " cells for " +
           std::to_string(raster.width) + " x " + std::to_string(raster.height);
  if (!(raster.resolution_m > 0) || !std::isfinite(raster.resolution_m) ||
      !raster.origin.allFinite())
    return "raster plan: resolution must be positive and the origin finite";
  return {};
}

// An occupied cell kept as a wall: its centre (plan frame), the main axis of the occupied
// cells around it, and their spread across that axis and along it (variances, cells^2).
struct WallCell {
  size_t index;  // row * width + col
  Eigen::Vector2d centre, dir;
  double across, along;
  // Lines start from the cells amid straight walls: the least spread across their wall for
  // its spread along it, then the most along it.
  bool Straighter(const WallCell& o) const {
    const double a = across * o.along, b = o.across * along;
    return a != b ? a < b : along > o.along;
  }
};

// The segment along dir over [lo, hi] from centre (metres), grown at both ends by half a
// cell's extent along dir: long enough that a diagonal wall's staircase of cells stays one
// line. A cell alone is its span over [0, 0].
Segment SpanAlong(const Eigen::Vector2d& centre, const Eigen::Vector2d& dir, double lo, double hi,
                  double res) {
  const double half = 0.5 * res * (std::abs(dir.x()) + std::abs(dir.y()));
  return {centre + (lo - half) * dir, centre + (hi + half) * dir};
}

// A cell whose own direction turns further than this from a line's (30 degrees) is at a
// corner or on another wall.
constexpr double kSameWallCos = 0.866;

// The cells as lines: from the straightest cell not yet on a line, every cell connected to
// it (8 neighbours) through cells within tolerance_m of the line along its direction, and
// running along it themselves, joins it. The line is then fitted to the union of the cells'
// segments (their centres' spread, and each segment's own, res^2 / 12, along the first
// cell's direction) and spans their projections. A wall of the raster becomes a few lines
// instead of a segment a cell, the same wall within tolerance_m, so that the closest-wall
// index lists a few candidates where it listed one for every cell around.
std::vector<Segment> FitLines(const std::vector<WallCell>& cells, int width, double res,
                              double tolerance_m) {
  std::vector<size_t> order(cells.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return cells[a].Straighter(cells[b]); });
  auto find = [&](long long row, long long col) -> std::optional<size_t> {
    if (row < 0 || col < 0 || col >= width) return std::nullopt;
    const size_t index = static_cast<size_t>(row) * width + static_cast<size_t>(col);
    const auto it = std::lower_bound(cells.begin(), cells.end(), index,
                                     [](const WallCell& c, size_t i) { return c.index < i; });
    if (it == cells.end() || it->index != index) return std::nullopt;
    return static_cast<size_t>(it - cells.begin());
  };
  std::vector<bool> taken(cells.size(), false);
  std::vector<Segment> lines;
  std::vector<size_t> members;
  for (const size_t seed : order) {
    if (taken[seed]) continue;
    taken[seed] = true;
    members.assign(1, seed);
    const Eigen::Vector2d c0 = cells[seed].centre, d0 = cells[seed].dir;
    for (size_t next = 0; next < members.size(); ++next) {
      const long long row = static_cast<long long>(cells[members[next]].index / width);
      const long long col = static_cast<long long>(cells[members[next]].index % width);
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const std::optional<size_t> k = find(row + dr, col + dc);
          if (!k || taken[*k]) continue;
          const Eigen::Vector2d off = cells[*k].centre - c0;
          if (std::abs(d0.x() * off.y() - d0.y() * off.x()) > tolerance_m * (1 + 1e-9)) continue;
          if (std::abs(cells[*k].dir.dot(d0)) < kSameWallCos) continue;
          taken[*k] = true;
          members.push_back(*k);
        }
      }
    }
    if (members.size() == 1) {
      lines.push_back(SpanAlong(c0, d0, 0, 0, res));
      continue;
    }
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const size_t m : members) mean += cells[m].centre;
    mean /= static_cast<double>(members.size());
    // Each cell's segment spreads res^2 / 12 along the seed's direction besides its centre.
    Eigen::Matrix2d scatter =
        (static_cast<double>(members.size()) * res * res / 12) * d0 * d0.transpose();
    for (const size_t m : members) {
      const Eigen::Vector2d off = cells[m].centre - mean;
      scatter += off * off.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
    const Eigen::Vector2d dir = eig.eigenvectors().col(1);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const size_t m : members) {
      const double t = (cells[m].centre - mean).dot(dir);
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
    lines.push_back(SpanAlong(mean, dir, lo, hi, res));
  }
  return lines;
}

}  // namespace

FloorPlanParse FloorPlanFromRaster(const OccupancyRaster& raster, std::string id,
                                   const RasterPlanOptions& options, RasterPlanReport* report) {
  FloorPlanParse out;
  out.error = RasterError(raster, options);
  if (!out.error.empty()) return out;
  const double res = raster.resolution_m;
  const int w = raster.width, h = raster.height;
  auto occupied = [&](int col, int row) {
    return col >= 0 && row >= 0 && col < w && row < h &&
           raster.occupied[static_cast<size_t>(row) * w + col] != 0;
  };
  const int reach = static_cast<int>(std::floor(options.direction_radius_cells));
  const double r2 = options.direction_radius_cells * options.direction_radius_cells;

  RasterPlanReport counts;
  std::vector<WallCell> cells;  // in row-major order
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      if (!occupied(col, row)) continue;
      ++counts.occupied;
      // Second moments of the neighbouring cells' offsets (in cells, y up).
      Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
      Eigen::Vector2d sum = Eigen::Vector2d::Zero();
      int n = 0;
      for (int dr = -reach; dr <= reach; ++dr) {
        for (int dc = -reach; dc <= reach; ++dc) {
          if (dc * dc + dr * dr > r2 || !occupied(col + dc, row + dr)) continue;
          const Eigen::Vector2d d(dc, -dr);
          scatter += d * d.transpose();
          sum += d;
          ++n;
        }
      }
      if (n - 1 < options.min_neighbours) {
        ++counts.isolated;
        continue;
      }
      const Eigen::Vector2d mean = sum / n;
      scatter = scatter / n - mean * mean.transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
      const Eigen::Vector2d centre =
          raster.origin + Eigen::Vector2d((col + 0.5) * res, (h - 1 - row + 0.5) * res);
      cells.push_back({static_cast<size_t>(row) * w + col, centre, eig.eigenvectors().col(1),
                       std::max(eig.eigenvalues()(0), 0.0), eig.eigenvalues()(1)});
    }
  }
  if (report) *report = counts;
  std::vector<Segment> raw = FitLines(cells, w, res, options.line_tolerance_cells * res);
  if (raw.empty()) {
    out.error = "raster plan: no occupied cells (" + std::to_string(counts.occupied) +
                " occupied, all isolated)";
    return out;
  }
  out = MakeFloorPlan(std::move(id), std::move(raw));
  out.dropped_segments += counts.isolated;
  return out;
}

}  // namespace floorpose
