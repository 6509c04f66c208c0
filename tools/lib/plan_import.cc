#include "tools/lib/plan_import.h"

#include <gdal.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

namespace floorpose::tools {
namespace {

// DXF $INSUNITS codes (AutoCAD's UnitsValue) in metres; 0 is "unitless".
const std::map<int, std::pair<double, const char*>> kInsUnits = {
    {1, {0.0254, "inches"}},    {2, {0.3048, "feet"}}, {4, {0.001, "millimetres"}},
    {5, {0.01, "centimetres"}}, {6, {1.0, "metres"}},  {14, {0.1, "decimetres"}},
};

// GDAL reads DXF headers but does not expose $INSUNITS: read the group-code pairs of the
// HEADER section ("9 / $INSUNITS / 70 / <code>"). Nothing when absent.
std::optional<int> DxfInsUnits(const std::string& path) {
  std::ifstream in(path);
  std::string code, value;
  for (int pairs = 0; pairs < 20000 && std::getline(in, code) && std::getline(in, value); ++pairs) {
    auto trim = [](std::string s) {
      s.erase(0, s.find_first_not_of(" \t\r"));
      s.erase(s.find_last_not_of(" \t\r") + 1);
      return s;
    };
    if (trim(value) == "ENDSEC") return std::nullopt;  // the header is the first section
    if (trim(code) == "9" && trim(value) == "$INSUNITS") {
      if (!std::getline(in, code) || !std::getline(in, value) || trim(code) != "70")
        return std::nullopt;
      try {
        return std::stoi(trim(value));
      } catch (...) {
        return std::nullopt;
      }
    }
  }
  return std::nullopt;
}

// The AIA CAD layer names (US National CAD Standard) by prefix, for files drawn to it.
const std::pair<const char*, LineKind> kAiaLayers[] = {
    {"A-WALL", LineKind::kWall},          {"A-DOOR", LineKind::kDoor},
    {"A-GLAZ", LineKind::kGlass},         {"A-WIND", LineKind::kWindow},
    {"A-FLOR-STRS", LineKind::kStairs},   {"A-STRS", LineKind::kStairs},
    {"A-FLOR-EVTR", LineKind::kElevator}, {"A-EVTR", LineKind::kElevator}};

bool LayerMatches(const std::string& pattern, const std::string& layer) {
  auto upper = [](std::string s) {
    for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return s;
  };
  const std::string p = upper(pattern), l = upper(layer);
  if (!p.empty() && p.back() == '*') return l.rfind(p.substr(0, p.size() - 1), 0) == 0;
  return p == l;
}

void AddGeometry(OGRGeometryH g, double scale, std::vector<Segment>* out, int depth = 0) {
  if (!g || depth > 8) return;
  const OGRwkbGeometryType type = wkbFlatten(OGR_G_GetGeometryType(g));
  if (type == wkbLineString || type == wkbLinearRing) {
    const int n = OGR_G_GetPointCount(g);
    for (int i = 1; i < n; ++i) {
      out->push_back({{OGR_G_GetX(g, i - 1) * scale, OGR_G_GetY(g, i - 1) * scale},
                      {OGR_G_GetX(g, i) * scale, OGR_G_GetY(g, i) * scale}});
    }
    return;
  }
  if (type == wkbPolygon || type == wkbMultiLineString || type == wkbMultiPolygon ||
      type == wkbGeometryCollection) {
    for (int i = 0; i < OGR_G_GetGeometryCount(g); ++i)
      AddGeometry(OGR_G_GetGeometryRef(g, i), scale, out, depth + 1);
    return;
  }
  if (OGR_GT_IsCurve(type) || OGR_GT_IsSurface(type) || type == wkbMultiCurve ||
      type == wkbMultiSurface) {
    // Arcs, circles and curved polygons: as line strings (GDAL's default stepping).
    OGRGeometryH linear = OGR_G_GetLinearGeometry(g, 0, nullptr);
    AddGeometry(linear, scale, out, depth + 1);
    OGR_G_DestroyGeometry(linear);
  }
}

// The scale to metres: --units, else a DXF's $INSUNITS, else metres.
bool ChooseUnits(const std::string& path, const std::string& driver, const std::string& units,
                 PlanImportReport* report, std::string* error) {
  if (units == "m") {
    report->scale = 1.0;
    report->units = "metres (--units)";
  } else if (units == "cm") {
    report->scale = 0.01;
    report->units = "centimetres (--units)";
  } else if (units == "mm") {
    report->scale = 0.001;
    report->units = "millimetres (--units)";
  } else if (!units.empty()) {
    *error = "unknown units '" + units + "' (m, cm or mm)";
    return false;
  } else if (driver == "DXF") {
    const std::optional<int> code = DxfInsUnits(path);
    const auto it = code ? kInsUnits.find(*code) : kInsUnits.end();
    if (it != kInsUnits.end()) {
      report->scale = it->second.first;
      report->units = std::string(it->second.second) + " ($INSUNITS " + std::to_string(*code) + ")";
    } else {
      report->units = code ? "metres assumed ($INSUNITS " + std::to_string(*code) +
                                 " is unitless or unknown; use --units)"
                           : "metres assumed (no $INSUNITS; use --units)";
    }
  } else {
    report->units = "metres (the file's coordinates)";
  }
  return true;
}

// A feature's segments, in metres, and its layer: a CAD file's "Layer" field, else the
// GDAL layer it is in.
struct Entity {
  std::string layer;
  std::vector<Segment> segments;
};

std::vector<Entity> ReadEntities(GDALDatasetH ds, PlanImportReport* report) {
  std::vector<Entity> entities;
  std::set<std::string> seen;
  for (int l = 0; l < GDALDatasetGetLayerCount(ds); ++l) {
    OGRLayerH layer = GDALDatasetGetLayer(ds, l);
    const std::string layer_name = OGR_L_GetName(layer);
    OGRFeatureDefnH defn = OGR_L_GetLayerDefn(layer);
    const int cad_layer_field = OGR_FD_GetFieldIndex(defn, "Layer");  // DXF, DWG
    OGR_L_ResetReading(layer);
    OGRFeatureH f = nullptr;
    while ((f = OGR_L_GetNextFeature(layer)) != nullptr) {
      ++report->features;
      Entity e{layer_name, {}};
      if (cad_layer_field >= 0 && OGR_F_IsFieldSetAndNotNull(f, cad_layer_field))
        e.layer = OGR_F_GetFieldAsString(f, cad_layer_field);
      seen.insert(e.layer);
      AddGeometry(OGR_F_GetGeometryRef(f), report->scale, &e.segments);
      entities.push_back(std::move(e));
      OGR_F_Destroy(f);
    }
  }
  report->layers_seen.assign(seen.begin(), seen.end());
  return entities;
}

// Which layers are kept, as what: --layer-map, else --layer as walls, else the AIA names
// when the file uses them, else (an empty map) everything as walls. A layer asked for
// that the file lacks is an error.
bool ChooseLayers(const std::string& path, const PlanImportOptions& options,
                  const PlanImportReport& report,
                  std::vector<std::pair<LineKind, std::string>>* map, std::string* error) {
  *map = options.layer_map;
  for (const std::string& l : options.layers) map->emplace_back(LineKind::kWall, l);
  auto in_file = [&](const std::string& pattern) {
    return std::any_of(report.layers_seen.begin(), report.layers_seen.end(),
                       [&](const std::string& l) { return LayerMatches(pattern, l); });
  };
  if (map->empty()) {
    for (const auto& [prefix, kind] : kAiaLayers)
      if (in_file(prefix + std::string("*"))) map->emplace_back(kind, prefix + std::string("*"));
    return true;
  }
  for (const auto& [kind, pattern] : *map) {
    if (in_file(pattern)) continue;
    *error = path + ": no layer '" + pattern + "' (layers: ";
    for (size_t i = 0; i < report.layers_seen.size(); ++i)
      *error += (i ? ", " : "") + report.layers_seen[i];
    *error += ")";
    return false;
  }
  return true;
}

// The entities' segments on the chosen layers, each of its layer's kind.
std::vector<PlanLine> ClassifyLines(const std::vector<Entity>& entities,
                                    const std::vector<std::pair<LineKind, std::string>>& map,
                                    PlanImportReport* report) {
  std::vector<PlanLine> lines;
  for (const Entity& e : entities) {
    std::optional<LineKind> kind;
    if (map.empty()) kind = LineKind::kWall;
    for (const auto& [k, pattern] : map)
      if (!kind && LayerMatches(pattern, e.layer)) kind = k;
    if (!kind || e.segments.empty()) {
      ++report->skipped_features;
      continue;
    }
    for (const Segment& s : e.segments) lines.push_back({s, *kind});
  }
  report->segments = lines.size();
  return lines;
}

}  // namespace

bool ImportPlan(const std::string& path, const PlanImportOptions& options, FloorPlan* plan,
                PlanImportReport* report, std::string* error) {
  *report = {};
  GDALAllRegister();
  CPLPushErrorHandler(CPLQuietErrorHandler);
  GDALDatasetH ds =
      GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr);
  const std::string gdal_error = CPLGetLastErrorMsg();
  CPLPopErrorHandler();
  if (!ds) {
    *error = path + ": not a vector file GDAL can read" +
             (gdal_error.empty() ? std::string() : " (" + gdal_error + ")");
    return false;
  }
  auto close = std::unique_ptr<void, void (*)(void*)>(ds, [](void* d) { GDALClose(d); });
  const std::string driver = GDALGetDriverShortName(GDALGetDatasetDriver(ds));
  if (!ChooseUnits(path, driver, options.units, report, error)) return false;
  const std::vector<Entity> entities = ReadEntities(ds, report);
  std::vector<std::pair<LineKind, std::string>> map;
  if (!ChooseLayers(path, options, *report, &map, error)) return false;
  const std::vector<PlanLine> lines = ClassifyLines(entities, map, report);
  FloorPlanParse parsed = MakeFloorPlan(std::filesystem::path(path).stem().string(), lines, {});
  if (!parsed.ok()) {
    *error = path + ": " + parsed.error + " on the chosen layers";
    return false;
  }
  // Metres "assumed" is the only case where nobody said what the numbers are.
  const bool stated = report->units.find("assumed") == std::string::npos;
  if (const std::string why = CheckPlanSize(parsed.plan, report->scale, stated); !why.empty()) {
    *error = path + ": " + why;
    return false;
  }
  report->dropped = parsed.dropped_segments;
  CountKinds(parsed.plan, &report->kept);
  *plan = std::move(parsed.plan);
  return true;
}

std::string CheckPlanSize(const FloorPlan& plan, double scale, bool units_stated) {
  const double across = (plan.max - plan.min).maxCoeff();
  char text[300];
  // The units that would make it a building of tens to hundreds of metres.
  auto hint = [&]() -> std::string {
    for (const auto& [name, metres] : {std::pair{"mm", 0.001}, std::pair{"cm", 0.01}}) {
      const double fixed = across / scale * metres;
      if (fixed <= 1000 && metres < scale) {
        std::snprintf(text, sizeof(text), "; with --units %s it is %.1f m across", name, fixed);
        return text;
      }
    }
    return "; give its drawing units with --units m|cm|mm";
  };
  if (across > 2000) {
    std::snprintf(text, sizeof(text), "the plan is %.0f m across, more than a building's 2 km",
                  across);
    const std::string why = text;
    return why + hint();
  }
  if (across > 1000 && !units_stated) {
    std::snprintf(text, sizeof(text),
                  "the plan is %.0f m across in metres assumed (no units in the file): a drawing "
                  "in millimetres or centimetres?",
                  across);
    const std::string why = text;
    return why + hint();
  }
  return {};
}

void CountKinds(const FloorPlan& plan, std::map<std::string, size_t>* kept) {
  for (size_t i = 0; i < plan.segments.size(); ++i) ++(*kept)[LineKindName(plan.KindOf(i))];
  for (const PlanLine& o : plan.openings) ++(*kept)[LineKindName(o.kind)];
  if (!plan.rooms.empty()) (*kept)["room"] += plan.rooms.size();
}

}  // namespace floorpose::tools
