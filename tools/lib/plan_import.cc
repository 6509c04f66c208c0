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

  if (options.units == "m") {
    report->scale = 1.0;
    report->units = "metres (--units)";
  } else if (options.units == "cm") {
    report->scale = 0.01;
    report->units = "centimetres (--units)";
  } else if (options.units == "mm") {
    report->scale = 0.001;
    report->units = "millimetres (--units)";
  } else if (!options.units.empty()) {
    *error = "unknown units '" + options.units + "' (m, cm or mm)";
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

  const std::set<std::string> wanted(options.layers.begin(), options.layers.end());
  std::set<std::string> seen;
  std::vector<Segment> raw;
  for (int l = 0; l < GDALDatasetGetLayerCount(ds); ++l) {
    OGRLayerH layer = GDALDatasetGetLayer(ds, l);
    const std::string layer_name = OGR_L_GetName(layer);
    OGRFeatureDefnH defn = OGR_L_GetLayerDefn(layer);
    const int cad_layer_field = OGR_FD_GetFieldIndex(defn, "Layer");  // DXF, DWG
    OGR_L_ResetReading(layer);
    OGRFeatureH f = nullptr;
    while ((f = OGR_L_GetNextFeature(layer)) != nullptr) {
      ++report->features;
      std::string name = layer_name;
      if (cad_layer_field >= 0 && OGR_F_IsFieldSetAndNotNull(f, cad_layer_field))
        name = OGR_F_GetFieldAsString(f, cad_layer_field);
      seen.insert(name);
      const size_t before = raw.size();
      if (wanted.empty() || wanted.count(name) || wanted.count(layer_name))
        AddGeometry(OGR_F_GetGeometryRef(f), report->scale, &raw);
      if (raw.size() == before) ++report->skipped_features;
      OGR_F_Destroy(f);
    }
  }
  report->layers_seen.assign(seen.begin(), seen.end());
  report->segments = raw.size();
  for (const std::string& w : wanted) {
    if (!seen.count(w)) {
      *error = path + ": no layer '" + w + "' (layers: ";
      for (size_t i = 0; i < report->layers_seen.size(); ++i)
        *error += (i ? ", " : "") + report->layers_seen[i];
      *error += ")";
      return false;
    }
  }
  FloorPlanParse parsed =
      MakeFloorPlan(std::filesystem::path(path).stem().string(), std::move(raw));
  if (!parsed.ok()) {
    *error = path + ": " + parsed.error + " on the chosen layers";
    return false;
  }
  report->dropped = parsed.dropped_segments;
  *plan = std::move(parsed.plan);
  return true;
}

}  // namespace floorpose::tools
