// `floorpose import`: a CAD or GIS floor plan, an IMDF archive or an OSM indoor map as the
// GeoJSON floorposed loads (tools/lib/plan_import.h, tools/lib/building_import.h).
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "platform/floor_plan_io.h"
#include "tools/floorpose/commands.h"
#include "tools/lib/building_import.h"
#include "tools/lib/plan_import.h"

namespace floorpose::tools {
namespace {

struct ImportOptions {
  std::string from, to;
  std::vector<std::string> layer_map;  // kind=LAYER
  double storey_m = 3.5;
  PlanImportOptions plan;
};

bool WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (out.flush()) return true;
  spdlog::error("{}: cannot write", path);
  return false;
}

void PrintKinds(const std::string& what, const std::map<std::string, size_t>& kept) {
  std::string line;
  for (const auto& [kind, n] : kept)
    line += (line.empty() ? "" : ", ") + std::to_string(n) + " " + kind;
  std::printf("  %-20s %s\n", what.c_str(), line.empty() ? "nothing" : line.c_str());
}

// IMDF and OSM: one plan per level; several levels make a .floors set beside --to.
int RunBuildingImport(const ImportOptions& o) {
  std::vector<ImportedLevel> levels;
  BuildingImportReport report;
  std::string error;
  const bool ok = IsOsm(o.from) ? ImportOsm(o.from, o.storey_m, &levels, &report, &error)
                                : ImportImdf(o.from, o.storey_m, &levels, &report, &error);
  if (!ok) {
    spdlog::error("{}", error);
    return 1;
  }
  std::printf("floorpose import: %s (%s) -> %s\n", o.from.c_str(), report.format.c_str(),
              o.to.c_str());
  std::printf("  frame                metres, %s\n", report.origin.c_str());
  if (!WriteLevels(levels, o.to, "floorpose import " + o.from, &error)) {
    spdlog::error("{}", error);
    return 1;
  }
  for (const ImportedLevel& l : levels) {
    char what[64];
    std::snprintf(what, sizeof what, "level %s (%.1f m)", l.id.c_str(), l.height_m);
    PrintKinds(what, report.kept[l.id]);
  }
  std::printf("  skipped              %zu features (no lines, no level, or nothing we draw)\n",
              report.skipped_features);
  return 0;
}

int RunImport(ImportOptions o) {
  for (const std::string& pair : o.layer_map) {
    const size_t eq = pair.find('=');
    LineKind kind;
    if (eq == std::string::npos || eq + 1 == pair.size() ||
        !ParseLineKind(pair.substr(0, eq), &kind)) {
      spdlog::error(
          "--layer-map {}: want KIND=LAYER (kind: wall, door, window, glass, stairs, "
          "elevator, exit)",
          pair);
      return 2;
    }
    o.plan.layer_map.emplace_back(kind, pair.substr(eq + 1));
  }
  if (IsImdf(o.from) || IsOsm(o.from)) return RunBuildingImport(o);
  FloorPlan plan;
  PlanImportReport report;
  std::string error;
  if (!ImportPlan(o.from, o.plan, &plan, &report, &error)) {
    spdlog::error("{}", error);
    return 1;
  }
  if (!WriteText(o.to, platform::ToGeoJson(plan, "floorpose import " + o.from))) return 1;
  std::string layers;
  for (const std::string& l : report.layers_seen) layers += (layers.empty() ? "" : ", ") + l;
  std::printf("floorpose import: %s -> %s\n", o.from.c_str(), o.to.c_str());
  std::printf("  units                %s\n", report.units.c_str());
  std::printf("  layers in the file   %s\n", layers.c_str());
  std::printf("  features             %zu read, %zu skipped (other layers or no lines)\n",
              report.features, report.skipped_features);
  PrintKinds("kept", report.kept);
  std::printf("  dropped              %zu segments (zero-length or duplicate)\n", report.dropped);
  std::printf("  extent               %.2f x %.2f m\n", plan.max.x() - plan.min.x(),
              plan.max.y() - plan.min.y());
  return 0;
}

}  // namespace

Run AddImportCommand(CLI::App& app) {
  auto o = std::make_shared<ImportOptions>();
  app.add_option("--from", o->from,
                 "DXF, GeoJSON, GeoPackage, Shapefile (any GDAL vector file), an IMDF archive "
                 "(.zip or folder) or OSM indoor XML (.osm)")
      ->required();
  app.add_option("--to", o->to,
                 "floor plan to write (.geojson); a .floors set for a building of several levels")
      ->required();
  app.add_option("--layer", o->plan.layers, "keep only this layer, as walls (repeatable)");
  app.add_option("--layer-map", o->layer_map,
                 "what a CAD layer's lines are, KIND=LAYER (a trailing * matches a prefix), e.g. "
                 "wall=A-WALL,door=A-DOOR,glass=A-GLAZ; default: the AIA names when the file "
                 "has them, else every layer as walls")
      ->delimiter(',');
  app.add_option("--units", o->plan.units, "drawing units (default: the file's, else metres)")
      ->check(CLI::IsMember({"m", "cm", "mm"}));
  app.add_option("--storey-m", o->storey_m,
                 "IMDF and OSM: the height between levels, metres (they give only their order)")
      ->capture_default_str();
  return [o] { return RunImport(*o); };
}

}  // namespace floorpose::tools
