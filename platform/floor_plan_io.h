// Floor plan files: GeoJSON (LineString, MultiLineString, Polygon and MultiPolygon rings,
// metres in a local frame; or RFC 7946 longitude/latitude, projected to metres about the
// south-west corner of the bounding box or `properties.origin`, platform/wgs84.h), the
// thesis' text format and raster plans (.yaml beside an
// image, platform/raster_plan_io.h). Chosen by extension.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "core/floor_plan.h"

namespace floorpose::platform {

// Never throws: failures come back in FloorPlanParse::error, naming the file.
FloorPlanParse LoadFloorPlan(const std::string& path);
FloorPlanParse ParseGeoJsonFloorPlan(std::string_view text, std::string id);
// The plan as GeoJSON that ParseGeoJsonFloorPlan reads back: one LineString feature per
// line with properties.kind (LineKind's name), one Polygon per room with kind "room" and
// its name, top-level properties {"units": "m", "source": ...}. Coordinates to 0.1 mm.
std::string ToGeoJson(const FloorPlan& plan, const std::string& source);

// A building of several floors: a `.floors` text file, one floor per line,
//   <floor id> <height of its floor above the set's zero, metres> <plan file>
// with '#' comments; plan files are relative to the set's directory. The plans of one set
// share one x-y frame (as a building's CAD floors do), so an alignment holds across them.
struct FloorEntry {
  std::string id;
  double height_m = 0;
  std::string plan_path;
};
struct FloorSet {
  std::vector<FloorEntry> floors;
  std::string error;  // empty on success; names the file and line
  bool ok() const { return error.empty(); }
  const FloorEntry* Find(const std::string& id) const;
  // The floor whose height is nearest `height_m`.
  const FloorEntry& Nearest(double height_m) const;
};
bool IsFloorSet(const std::string& path);  // by its extension, .floors
FloorSet LoadFloorSet(const std::string& path);
// `dir` resolves relative plan paths; `name` prefixes errors.
FloorSet ParseFloorSet(std::string_view text, const std::string& dir, const std::string& name);

// A plan directory (the daemon's `plan_dir`): plans are addressed by id, the file name
// without its extension (.geojson, .json, .txt, .yaml or .floors). Ids are plain names (letters,
// digits,
// '-', '_', '.', not starting with '.'), so an id never leaves the directory.
// Sorted ids of the plans in dir; empty when it is missing or unreadable.
std::vector<std::string> ListPlanIds(const std::string& dir);
// The file of plan `id` in dir, or an error (invalid id, no plan directory, no such plan).
bool FindPlanFile(const std::string& dir, const std::string& id, std::string* path,
                  std::string* error);

// Reads a whole file of at most max_bytes; returns false with a message otherwise.
bool ReadFile(const std::string& path, size_t max_bytes, std::string* contents, std::string* error);

}  // namespace floorpose::platform
