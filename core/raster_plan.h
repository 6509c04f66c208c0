// Raster floor plans (a scanned evacuation plan, an occupancy map) as wall segments, so
// that they go into the same closest-wall index as vector plans: every occupied cell has
// a local wall direction (the main axis of the occupied cells around it), and connected
// cells along one line become one segment, so registration gets the wall's normal and the
// index a few candidates where a segment a cell would give dozens.
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
  // Connected wall cells within this many cells of a line along their direction become one
  // segment (the raster's own resolution: a wall two cells thick is one line between them).
  double line_tolerance_cells = 1.0;
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
