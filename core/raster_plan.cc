#include "core/raster_plan.h"

#include <Eigen/Eigenvalues>
#include <cmath>

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
  std::vector<Segment> raw;
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
      const Eigen::Vector2d dir = eig.eigenvectors().col(1);  // largest eigenvalue
      // Long enough that a diagonal wall's staircase of cells stays one line.
      const double half = 0.5 * res * (std::abs(dir.x()) + std::abs(dir.y()));
      const Eigen::Vector2d centre =
          raster.origin + Eigen::Vector2d((col + 0.5) * res, (h - 1 - row + 0.5) * res);
      raw.push_back({centre - half * dir, centre + half * dir});
    }
  }
  if (report) *report = counts;
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
