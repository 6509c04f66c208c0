// `floorpose import` as functions: CAD and GIS floor plans (DXF, GeoJSON, GeoPackage,
// Shapefile, anything GDAL/OGR reads as vectors) to the wall segments floorposed loads.
#pragma once

#include <string>
#include <vector>

#include "core/floor_plan.h"

namespace floorpose::tools {

struct PlanImportOptions {
  // Keep only these layers: OGR layer names, or for CAD files (one OGR layer) the CAD
  // layer of each entity (the "Layer" field). Empty keeps every layer.
  std::vector<std::string> layers;
  // Drawing units: "m", "cm" or "mm"; empty takes them from the file (DXF $INSUNITS),
  // else metres.
  std::string units;
};

struct PlanImportReport {
  size_t features = 0;                   // read
  size_t skipped_features = 0;           // on other layers, or without lines
  size_t segments = 0;                   // lines and polygon rings split into segments
  size_t dropped = 0;                    // zero-length or duplicate
  double scale = 1.0;                    // drawing unit in metres
  std::string units;                     // what the drawing unit is and where it came from
  std::vector<std::string> layers_seen;  // every layer name met, sorted
};

// Reads `path` through OGR (DXF blocks exploded), keeps the chosen layers' lines and
// polygon rings as segments in metres, drops zero-length and duplicate ones. False with
// a message naming the file on unreadable input or when nothing is left.
bool ImportPlan(const std::string& path, const PlanImportOptions& options, FloorPlan* plan,
                PlanImportReport* report, std::string* error);

}  // namespace floorpose::tools
