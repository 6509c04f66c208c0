// `floorpose import` of whole buildings, published as indoor maps: Apple's Indoor Mapping
// Data Format (IMDF, an OGC Community Standard) and OpenStreetMap's Simple Indoor Tagging.
// Each level becomes a floor plan with its lines' kinds and named rooms, in metres about
// one origin (the south-west corner of the whole building), so that the levels share one
// x-y frame as a .floors set wants.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/floor_plan.h"

namespace floorpose::tools {

struct ImportedLevel {
  std::string id;       // the level's short name, or its ordinal / OSM level
  double height_m = 0;  // above the lowest level's ordinal 0
  FloorPlan plan;
};

struct BuildingImportReport {
  std::string format;  // "IMDF" or "OSM indoor"
  std::string origin;  // the projection's origin, for the log
  std::map<std::string, std::map<std::string, size_t>> kept;  // level id -> kind -> lines
  size_t skipped_features = 0;  // without lines, on no level, of no kind we draw
};

// Whether `path` is an IMDF archive: a folder or .zip holding unit.geojson.
bool IsImdf(const std::string& path);
// Whether `path` is OSM XML (.osm).
bool IsOsm(const std::string& path);

// IMDF: every level to a plan; units' outlines to walls (stairs and elevator units to
// their kinds; an edge two walkways share is open), with their names as rooms; openings
// to doors (emergency exits and principal entrances to exits), cutting the walls they lie
// on; fixtures' outlines to walls (obstacles). Levels stand storey_m apart per ordinal.
bool ImportImdf(const std::string& path, double storey_m, std::vector<ImportedLevel>* levels,
                BuildingImportReport* report, std::string* error);

// OSM indoor (through GDAL's OSM driver): indoor=wall ways to walls, indoor=room outlines
// to walls and named rooms (corridors and areas to rooms without walls), stairs=yes rooms
// to stairs, door=* and window=* ways to doors and windows, door=*, entrance=* and
// window=* nodes to openings 0.9 m (doors) or 1.2 m (windows) wide along the wall they
// are on; level=* to levels, storey_m apart per level number.
bool ImportOsm(const std::string& path, double storey_m, std::vector<ImportedLevel>* levels,
               BuildingImportReport* report, std::string* error);

// Writes the levels as floorposed loads them: one level to `to` (.geojson), or several
// (or any, when `to` ends in .floors) to <stem>-<level>.geojson beside a .floors set at
// `to`, each level at its height. False with a message when a file cannot be written or
// several levels are to go to one .geojson.
bool WriteLevels(const std::vector<ImportedLevel>& levels, const std::string& to,
                 const std::string& source, std::string* error);

}  // namespace floorpose::tools
