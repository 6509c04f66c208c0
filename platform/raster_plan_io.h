// Raster floor plans on disk: a PNG (or any image libpng reads) with a YAML beside it in
// the ROS map_server convention:
//
//   image: plan.png              # relative to the YAML's directory
//   resolution: 0.05             # metres per pixel
//   origin: [x, y, 0.0]          # lower-left corner of the bottom-left pixel; yaw must be 0
//   negate: 0                    # 1: white is occupied
//   occupied_thresh: 0.65        # occupancy (1 - grey / 255) above this is a wall
//   free_thresh: 0.196           # read and checked, not needed for walls
#pragma once

#include <string>

#include "core/floor_plan.h"
#include "core/raster_plan.h"

namespace floorpose::platform {

// Never throws: failures come back in FloorPlanParse::error, naming the file.
FloorPlanParse LoadRasterFloorPlan(const std::string& yaml_path,
                                   RasterPlanReport* report = nullptr);

// The image as an occupancy raster with the YAML's geometry (for tools that draw it).
bool LoadOccupancyRaster(const std::string& yaml_path, OccupancyRaster* raster, std::string* error);

}  // namespace floorpose::platform
