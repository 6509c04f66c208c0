// `floorpose import` as functions: CAD and GIS floor plans (DXF, GeoJSON, GeoPackage,
// Shapefile, anything GDAL/OGR reads as vectors) to the wall segments floorposed loads.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/floor_plan.h"

namespace floorpose::tools {

struct PlanImportOptions {
  // Keep only these layers, as walls: OGR layer names, or for CAD files (one OGR layer)
  // the CAD layer of each entity (the "Layer" field).
  std::vector<std::string> layers;
  // What each CAD layer's lines are (--layer-map wall=A-WALL,door=A-DOOR,...): a layer
  // name, or a prefix ending in '*'. Empty, and without `layers`: the AIA names (A-WALL,
  // A-DOOR, A-GLAZ, A-WIND, A-STRS, A-EVTR and their A-FLOR- forms, by prefix) when the
  // file has any, else every layer as walls.
  std::vector<std::pair<LineKind, std::string>> layer_map;
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
  std::map<std::string, size_t> kept;    // lines kept per kind (LineKindName), and "room"
};

// Reads `path` through OGR (DXF blocks exploded), keeps the chosen layers' lines and
// polygon rings as segments of their kind in metres, drops zero-length and duplicate
// ones. False with a message naming the file on unreadable input, when nothing is left,
// or when the plan is not one building's size (CheckPlanSize).
bool ImportPlan(const std::string& path, const PlanImportOptions& options, FloorPlan* plan,
                PlanImportReport* report, std::string* error);

// A plan more than 2 km across is not one building; one over 1 km whose units nobody
// stated (no --units, no $INSUNITS) is a drawing in millimetres or centimetres read as
// metres. Empty when the size is plausible, else the reason with the --units that fits.
std::string CheckPlanSize(const FloorPlan& plan, double scale, bool units_stated);

// Counts a plan's lines per kind and its rooms into `kept`.
void CountKinds(const FloorPlan& plan, std::map<std::string, size_t>* kept);

}  // namespace floorpose::tools
