// Floor plan files: GeoJSON (LineString, MultiLineString, Polygon and MultiPolygon rings,
// metres in a local frame), the thesis' text format and raster plans (.yaml beside an
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

// A plan directory (the daemon's `plan_dir`): plans are addressed by id, the file name
// without its extension (.geojson, .json, .txt or .yaml). Ids are plain names (letters, digits,
// '-', '_', '.', not starting with '.'), so an id never leaves the directory.
// Sorted ids of the plans in dir; empty when it is missing or unreadable.
std::vector<std::string> ListPlanIds(const std::string& dir);
// The file of plan `id` in dir, or an error (invalid id, no plan directory, no such plan).
bool FindPlanFile(const std::string& dir, const std::string& id, std::string* path,
                  std::string* error);

// Reads a whole file of at most max_bytes; returns false with a message otherwise.
bool ReadFile(const std::string& path, size_t max_bytes, std::string* contents, std::string* error);

}  // namespace floorpose::platform
