// Raster floor plans (a scanned evacuation plan, an occupancy map) as wall segments, so
// that they go into the same closest-wall index as vector plans: every occupied cell
// becomes a short segment through its centre along the local wall direction (the main
// axis of the occupied cells around it), so registration gets the wall's normal too.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/floor_plan.h"

namespace floorpose {

// An occupancy grid in the ROS map_server convention: row 0 is the top (largest y).
struct OccupancyRaster {
  int width = 0, height = 0;
  std::vector<uint8_t> occupied;  // width * height, row-major from the top row; 0 or 1
  double resolution_m = 0.05;     // cell size
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  // lower-left corner of the bottom-left cell
};

struct RasterPlanOptions {
  // The wall direction at a cell is the main axis of the occupied cells within this many
  // cells of it.
  double direction_radius_cells = 2.5;
  // Cells with fewer occupied neighbours within that radius are noise (a speck the
  // scanner or the scan left) and are dropped.
  int min_neighbours = 2;
  size_t max_cells = size_t{1} << 26;  // larger rasters are refused (64 M cells)
};

struct RasterPlanReport {
  size_t occupied = 0;  // occupied cells
  size_t isolated = 0;  // dropped as noise
};

// The segments of the occupied cells (dropped ones count in dropped_segments). Fails on
// a malformed raster or one without a usable occupied cell.
FloorPlanParse FloorPlanFromRaster(const OccupancyRaster& raster, std::string id,
                                   const RasterPlanOptions& options = {},
                                   RasterPlanReport* report = nullptr);

}  // namespace floorpose
