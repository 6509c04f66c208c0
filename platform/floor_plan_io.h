// Floor plan files: GeoJSON (LineString, MultiLineString, Polygon and MultiPolygon rings,
// metres in a local frame) and the thesis' text format. Chosen by extension.
#pragma once

#include <string>
#include <string_view>

#include "core/floor_plan.h"

namespace floorpose::platform {

// Never throws: failures come back in FloorPlanParse::error, naming the file.
FloorPlanParse LoadFloorPlan(const std::string& path);
FloorPlanParse ParseGeoJsonFloorPlan(std::string_view text, std::string id);

// Reads a whole file of at most max_bytes; returns false with a message otherwise.
bool ReadFile(const std::string& path, size_t max_bytes, std::string* contents, std::string* error);

}  // namespace floorpose::platform
