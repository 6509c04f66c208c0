#include "tools/lib/building_import.h"

#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <ogr_api.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <tuple>

#include "platform/floor_plan_io.h"
#include "platform/wgs84.h"
#include "tools/lib/plan_import.h"

namespace floorpose::tools {
namespace {

using Json = nlohmann::json;
using Polyline = std::vector<Eigen::Vector2d>;

// One level as read, in longitude/latitude: lines of a kind, named room outlines, and
// points on walls where an opening of a kind and width is (OSM's door and window nodes).
struct RawLevel {
  std::string id;
  double ordinal = 0;
  std::vector<std::pair<Polyline, LineKind>> lines;
  std::vector<std::pair<std::string, Polyline>> rooms;
  struct Mark {
    Eigen::Vector2d at;
    LineKind kind;
    double width_m;
  };
  std::vector<Mark> marks;
};

// The rings and line strings of a GeoJSON geometry (IMDF), each as a polyline.
void GeoJsonPolylines(const Json& g, std::vector<Polyline>* out) {
  if (!g.is_object() || !g.contains("coordinates")) return;
  const std::string type = g.value("type", "");
  auto line = [&](const Json& coords) {
    Polyline p;
    for (const Json& c : coords)
      if (c.is_array() && c.size() >= 2 && c[0].is_number() && c[1].is_number())
        p.emplace_back(c[0].get<double>(), c[1].get<double>());
    if (p.size() >= 2) out->push_back(std::move(p));
  };
  const Json& c = g["coordinates"];
  if (!c.is_array()) return;
  if (type == "LineString") line(c);
  if (type == "MultiLineString" || type == "Polygon")
    for (const Json& l : c) line(l);
  if (type == "MultiPolygon")
    for (const Json& poly : c)
      if (poly.is_array())
        for (const Json& l : poly) line(l);
}

// An IMDF name ({"en": "Lab B", ...}): English when there, else the first language.
std::string ImdfName(const Json& props) {
  if (!props.contains("name") || !props["name"].is_object() || props["name"].empty()) return {};
  const Json& n = props["name"];
  if (n.contains("en") && n["en"].is_string()) return n["en"];
  for (const auto& [lang, v] : n.items())
    if (v.is_string()) return v;
  return {};
}

// Reads a whole file through GDAL's virtual file system (a folder or /vsizip/).
bool ReadVsi(const std::string& path, std::string* text) {
  VSILFILE* f = VSIFOpenL(path.c_str(), "rb");
  if (!f) return false;
  char buffer[1 << 16];
  size_t n = 0;
  while ((n = VSIFReadL(buffer, 1, sizeof buffer, f)) > 0) {
    text->append(buffer, n);
    if (text->size() > (512u << 20)) break;
  }
  VSIFCloseL(f);
  return true;
}

// The IMDF files of an archive (a folder or a .zip, the files at its top or in one
// folder), by name: "unit.geojson" -> its path for VSI.
std::map<std::string, std::string> ImdfFiles(const std::string& path) {
  const std::string base = std::filesystem::is_directory(path) ? path : "/vsizip/" + path;
  std::map<std::string, std::string> files;
  char** list = VSIReadDirRecursive(base.c_str());
  for (char** p = list; p && *p; ++p) {
    const std::string rel = *p;
    const std::string name = std::filesystem::path(rel).filename().string();
    if (name.size() > 8 && name.substr(name.size() - 8) == ".geojson" && !files.count(name))
      files[name] = base + "/" + rel;
  }
  CSLDestroy(list);
  return files;
}

// Projects every level about the south-west corner of them all and builds the plans.
bool FinishLevels(std::vector<RawLevel> raw, double storey_m, std::vector<ImportedLevel>* levels,
                  BuildingImportReport* report, std::string* error) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300);
  std::vector<Eigen::Vector2d*> all;
  for (RawLevel& l : raw) {
    for (auto& [line, kind] : l.lines)
      for (Eigen::Vector2d& p : line) all.push_back(&p);
    for (auto& [name, outline] : l.rooms)
      for (Eigen::Vector2d& p : outline) all.push_back(&p);
    for (RawLevel::Mark& m : l.marks) all.push_back(&m.at);
  }
  for (const Eigen::Vector2d* p : all)
    if (p->allFinite()) lo = lo.cwiseMin(*p);
  if (all.empty()) {
    *error = "no lines on any level";
    return false;
  }
  std::vector<Eigen::Vector2d> points;
  points.reserve(all.size());
  for (const Eigen::Vector2d* p : all) points.push_back(*p);
  if (!platform::ProjectToLocalMetres(lo, &points, error)) return false;
  for (size_t i = 0; i < all.size(); ++i) *all[i] = points[i];
  char origin[120];
  std::snprintf(origin, sizeof origin, "WGS84 azimuthal equidistant about %.7f, %.7f", lo.x(),
                lo.y());
  report->origin = origin;

  std::sort(raw.begin(), raw.end(),
            [](const RawLevel& a, const RawLevel& b) { return a.ordinal < b.ordinal; });
  for (RawLevel& l : raw) {
    std::vector<PlanLine> lines;
    for (const auto& [line, kind] : l.lines)
      for (size_t i = 1; i < line.size(); ++i) lines.push_back({{line[i - 1], line[i]}, kind});
    // A door or window node is an opening of its width along the wall it is on.
    for (const RawLevel::Mark& m : l.marks) {
      const Segment* best = nullptr;
      double nearest = 0.5;
      for (const PlanLine& w : lines) {
        if (IsOpening(w.kind)) continue;
        const double d = (ClosestPointOnSegment(w.segment, m.at) - m.at).norm();
        if (d < nearest) nearest = d, best = &w.segment;
      }
      if (!best || !(best->Length() > 0)) {
        ++report->skipped_features;
        continue;
      }
      const Eigen::Vector2d along = (best->b - best->a).normalized() * (0.5 * m.width_m);
      const Eigen::Vector2d at = ClosestPointOnSegment(*best, m.at);
      lines.push_back({{at - along, at + along}, m.kind});
    }
    std::vector<PlanRoom> rooms;
    for (auto& [name, outline] : l.rooms) rooms.push_back({name, outline});
    FloorPlanParse parsed = MakeFloorPlan(l.id, lines, std::move(rooms));
    if (!parsed.ok()) {
      ++report->skipped_features;
      continue;  // a level with nothing but labels
    }
    CountKinds(parsed.plan, &report->kept[l.id]);
    levels->push_back({l.id, l.ordinal * storey_m, std::move(parsed.plan)});
  }
  if (levels->empty()) {
    *error = "no level with walls";
    return false;
  }
  return true;
}

// OSM's other_tags, an HSTORE string ("k"=>"v","k2"=>"v2"), and the named fields.
std::map<std::string, std::string> OsmTags(OGRFeatureH f) {
  std::map<std::string, std::string> tags;
  OGRFeatureDefnH defn = OGR_F_GetDefnRef(f);
  for (int i = 0; i < OGR_FD_GetFieldCount(defn); ++i) {
    if (!OGR_F_IsFieldSetAndNotNull(f, i)) continue;
    const std::string name = OGR_Fld_GetNameRef(OGR_FD_GetFieldDefn(defn, i));
    const std::string value = OGR_F_GetFieldAsString(f, i);
    if (name != "other_tags") {
      tags[name] = value;
      continue;
    }
    // "key"=>"value" pairs, quotes escaped with a backslash.
    std::vector<std::string> parts;
    std::string cur;
    bool quoted = false;
    for (size_t k = 0; k < value.size(); ++k) {
      const char c = value[k];
      if (c == '\\' && k + 1 < value.size()) {
        cur += value[++k];
      } else if (c == '"') {
        if (quoted) parts.push_back(cur), cur.clear();
        quoted = !quoted;
      } else if (quoted) {
        cur += c;
      }
    }
    for (size_t k = 0; k + 1 < parts.size(); k += 2) tags[parts[k]] = parts[k + 1];
  }
  return tags;
}

void OgrPolylines(OGRGeometryH g, std::vector<Polyline>* out, int depth = 0) {
  if (!g || depth > 8) return;
  const OGRwkbGeometryType type = wkbFlatten(OGR_G_GetGeometryType(g));
  if (type == wkbLineString || type == wkbLinearRing) {
    Polyline p;
    for (int i = 0; i < OGR_G_GetPointCount(g); ++i)
      p.emplace_back(OGR_G_GetX(g, i), OGR_G_GetY(g, i));
    if (p.size() >= 2) out->push_back(std::move(p));
    return;
  }
  for (int i = 0; i < OGR_G_GetGeometryCount(g); ++i)
    OgrPolylines(OGR_G_GetGeometryRef(g, i), out, depth + 1);
}

// IMDF levels by feature id: ordinal, and an id from the short name (else "L<ordinal>").
std::map<std::string, RawLevel> ImdfLevels(const Json& level_doc) {
  std::map<std::string, RawLevel> by_id;
  for (const Json& f : level_doc["features"]) {
    if (!f.is_object() || !f.contains("id") || !f["id"].is_string()) continue;
    const Json props = f.value("properties", Json::object());
    RawLevel l;
    l.ordinal = props.contains("ordinal") && props["ordinal"].is_number()
                    ? props["ordinal"].get<double>()
                    : 0.0;
    std::string shortname;
    if (props.contains("short_name") && props["short_name"].is_object())
      shortname = ImdfName(Json{{"name", props["short_name"]}});
    l.id = shortname.empty() ? "L" + std::to_string(static_cast<int>(l.ordinal)) : shortname;
    for (char& c : l.id)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
    by_id[f["id"]] = std::move(l);
  }
  return by_id;
}

// Each feature of an IMDF file to take(level, properties, polylines), or counted as skipped
// (no known level_id, or no geometry).
template <typename Take>
void ForEachOnLevel(const Json& doc, std::map<std::string, RawLevel>& by_id,
                    BuildingImportReport* report, const Take& take) {
  for (const Json& f : doc["features"]) {
    const Json props = f.is_object() ? f.value("properties", Json::object()) : Json::object();
    const std::string level = props.contains("level_id") && props["level_id"].is_string()
                                  ? props["level_id"].get<std::string>()
                                  : std::string();
    std::vector<Polyline> lines;
    if (f.is_object() && f.contains("geometry")) GeoJsonPolylines(f["geometry"], &lines);
    if (!by_id.count(level) || lines.empty()) {
      ++report->skipped_features;
      continue;
    }
    take(by_id[level], props, std::move(lines));
  }
}

// An edge as a key independent of its direction, to about 1 cm (degrees times 1e7).
using EdgeKey = std::tuple<std::pair<long long, long long>, std::pair<long long, long long>>;
EdgeKey KeyOf(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  auto q = [](double v) { return std::llround(v * 1e7); };
  auto ka = std::make_pair(q(a.x()), q(a.y())), kb = std::make_pair(q(b.x()), q(b.y()));
  return std::make_tuple(std::min(ka, kb), std::max(ka, kb));
}

// A unit's outline as lines of its kind, broken where an edge is open floor.
void AddUnitOutline(const Polyline& ring, LineKind kind, bool walkway,
                    std::map<EdgeKey, int>& walkway_edges, RawLevel& l) {
  Polyline piece;
  for (size_t i = 0; i < ring.size(); ++i) {
    const bool open = walkway && i > 0 && walkway_edges[KeyOf(ring[i - 1], ring[i])] > 1;
    if (open || i == 0) {
      if (piece.size() >= 2) l.lines.emplace_back(piece, kind);
      piece.clear();
    }
    piece.push_back(ring[i]);
  }
  if (piece.size() >= 2) l.lines.emplace_back(piece, kind);
}

// IMDF units: outlines are walls (stairs and elevators their own kinds), except an edge
// two walkways share (open floor); a named unit is a room.
void AddImdfUnits(const Json& unit_doc, std::map<std::string, RawLevel>& by_id,
                  BuildingImportReport* report) {
  std::map<EdgeKey, int> walkway_edges;
  for (const Json& f : unit_doc["features"]) {
    const Json props = f.is_object() ? f.value("properties", Json::object()) : Json::object();
    if (props.value("category", "") != "walkway" || !f.contains("geometry")) continue;
    std::vector<Polyline> rings;
    GeoJsonPolylines(f["geometry"], &rings);
    for (const Polyline& r : rings)
      for (size_t i = 1; i < r.size(); ++i) ++walkway_edges[KeyOf(r[i - 1], r[i])];
  }
  ForEachOnLevel(unit_doc, by_id, report,
                 [&](RawLevel& l, const Json& props, std::vector<Polyline> rings) {
                   const std::string category = props.value("category", "");
                   const LineKind kind = category == "stairs"     ? LineKind::kStairs
                                         : category == "elevator" ? LineKind::kElevator
                                                                  : LineKind::kWall;
                   for (const Polyline& r : rings)
                     AddUnitOutline(r, kind, category == "walkway", walkway_edges, l);
                   const std::string name = ImdfName(props);
                   if (!name.empty()) l.rooms.emplace_back(name, rings.front());
                 });
}

}  // namespace

bool IsImdf(const std::string& path) {
  const std::filesystem::path p(path);
  if (!std::filesystem::is_directory(p) && p.extension() != ".zip") return false;
  return ImdfFiles(path).count("unit.geojson") > 0;
}

bool IsOsm(const std::string& path) { return std::filesystem::path(path).extension() == ".osm"; }

bool ImportImdf(const std::string& path, double storey_m, std::vector<ImportedLevel>* levels,
                BuildingImportReport* report, std::string* error) {
  report->format = "IMDF";
  const std::map<std::string, std::string> files = ImdfFiles(path);
  auto features = [&](const std::string& name, Json* doc) -> bool {
    std::string text;
    if (!files.count(name) || !ReadVsi(files.at(name), &text)) return false;
    *doc = Json::parse(text, nullptr, false);
    return doc->is_object() && doc->contains("features") && (*doc)["features"].is_array();
  };
  Json level_doc, unit_doc;
  if (!features("level.geojson", &level_doc) || !features("unit.geojson", &unit_doc)) {
    *error = path + ": an IMDF archive needs level.geojson and unit.geojson";
    return false;
  }
  std::map<std::string, RawLevel> by_id = ImdfLevels(level_doc);
  AddImdfUnits(unit_doc, by_id, report);
  Json doc;
  if (features("opening.geojson", &doc))
    ForEachOnLevel(
        doc, by_id, report, [&](RawLevel& l, const Json& props, std::vector<Polyline> lines) {
          const std::string category = props.value("category", "");
          const LineKind kind = category == "emergencyexit" || category == "pedestrian.principal"
                                    ? LineKind::kExit
                                    : LineKind::kDoor;
          for (Polyline& p : lines) l.lines.emplace_back(std::move(p), kind);
        });
  if (features("fixture.geojson", &doc))
    ForEachOnLevel(doc, by_id, report, [&](RawLevel& l, const Json&, std::vector<Polyline> rings) {
      for (Polyline& p : rings) l.lines.emplace_back(std::move(p), LineKind::kWall);
    });
  std::vector<RawLevel> raw;
  for (auto& [id, l] : by_id) raw.push_back(std::move(l));
  if (!FinishLevels(std::move(raw), storey_m, levels, report, error)) {
    *error = path + ": " + *error;
    return false;
  }
  return true;
}

bool ImportOsm(const std::string& path, double storey_m, std::vector<ImportedLevel>* levels,
               BuildingImportReport* report, std::string* error) {
  report->format = "OSM indoor";
  GDALAllRegister();
  GDALDatasetH ds =
      GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr);
  if (!ds) {
    *error = path + ": not OSM XML GDAL can read";
    return false;
  }
  auto close = std::unique_ptr<void, void (*)(void*)>(ds, [](void* d) { GDALClose(d); });
  std::map<std::string, RawLevel> by_level;
  auto level_of = [&](const std::map<std::string, std::string>& tags) -> RawLevel& {
    std::string id = tags.count("level") ? tags.at("level") : "0";
    id = id.substr(0, id.find(';'));  // a feature on several levels: its first
    RawLevel& l = by_level[id];
    l.id = id;
    try {
      l.ordinal = std::stod(id);
    } catch (...) {
      l.ordinal = 0;
    }
    return l;
  };
  // The OSM driver wants its layers read in order: points, lines, multilinestrings,
  // multipolygons, other_relations.
  for (int i = 0; i < GDALDatasetGetLayerCount(ds); ++i) {
    OGRLayerH layer = GDALDatasetGetLayer(ds, i);
    OGR_L_ResetReading(layer);
    OGRFeatureH f = nullptr;
    while ((f = OGR_L_GetNextFeature(layer)) != nullptr) {
      const std::map<std::string, std::string> tags = OsmTags(f);
      auto tag = [&](const char* k) { return tags.count(k) ? tags.at(k) : std::string(); };
      std::vector<Polyline> lines;
      OgrPolylines(OGR_F_GetGeometryRef(f), &lines);
      OGRGeometryH g = OGR_F_GetGeometryRef(f);
      const bool point = g && wkbFlatten(OGR_G_GetGeometryType(g)) == wkbPoint;
      const std::string indoor = tag("indoor"), door = tag("door"), window = tag("window");
      const std::string entrance = tag("entrance");
      bool used = false;
      if (point && (!door.empty() || !entrance.empty() || !window.empty())) {
        const LineKind kind = !window.empty() && door.empty() && entrance.empty()
                                  ? LineKind::kWindow
                              : !entrance.empty() ? LineKind::kExit
                                                  : LineKind::kDoor;
        level_of(tags).marks.push_back(
            {{OGR_G_GetX(g, 0), OGR_G_GetY(g, 0)}, kind, kind == LineKind::kWindow ? 1.2 : 0.9});
        used = true;
      } else if (!lines.empty() && (!indoor.empty() || !door.empty() || !window.empty())) {
        RawLevel& l = level_of(tags);
        used = true;
        if (!door.empty() || !window.empty()) {
          for (Polyline& p : lines)
            l.lines.emplace_back(std::move(p), door.empty() ? LineKind::kWindow : LineKind::kDoor);
        } else if (indoor == "wall") {
          for (Polyline& p : lines) l.lines.emplace_back(std::move(p), LineKind::kWall);
        } else if (indoor == "room" || indoor == "corridor" || indoor == "area") {
          if (tags.count("name")) l.rooms.emplace_back(tag("name"), lines.front());
          const LineKind kind = tag("stairs") == "yes" ? LineKind::kStairs : LineKind::kWall;
          if (indoor == "room")
            for (Polyline& p : lines) l.lines.emplace_back(std::move(p), kind);
        } else {
          used = false;
        }
      }
      if (!used) ++report->skipped_features;
      OGR_F_Destroy(f);
    }
  }
  std::vector<RawLevel> raw;
  for (auto& [id, l] : by_level) raw.push_back(std::move(l));
  if (!FinishLevels(std::move(raw), storey_m, levels, report, error)) {
    *error = path + ": " + *error;
    return false;
  }
  return true;
}

namespace {

bool WriteText(const std::string& path, const std::string& text, std::string* error) {
  std::ofstream out(path);
  out << text;
  if (out.flush()) return true;
  *error = path + ": cannot write";
  return false;
}

}  // namespace

bool WriteLevels(const std::vector<ImportedLevel>& levels, const std::string& to,
                 const std::string& source, std::string* error) {
  const std::filesystem::path path(to);
  if (levels.size() == 1 && path.extension() != ".floors")
    return WriteText(to, platform::ToGeoJson(levels[0].plan, source), error);
  if (path.extension() != ".floors") {
    *error = std::to_string(levels.size()) + " levels: the output must be a .floors set";
    return false;
  }
  std::string set = "# " + source + ": floor, height (m), plan\n";
  for (const ImportedLevel& l : levels) {
    const std::string file = path.stem().string() + "-" + l.id + ".geojson";
    if (!WriteText((path.parent_path() / file).string(),
                   platform::ToGeoJson(l.plan, source + ", level " + l.id), error))
      return false;
    char line[256];
    std::snprintf(line, sizeof line, "%s %.2f %s\n", l.id.c_str(), l.height_m, file.c_str());
    set += line;
  }
  return WriteText(to, set, error);
}

}  // namespace floorpose::tools
