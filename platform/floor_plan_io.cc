#include "platform/floor_plan_io.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>

#include "platform/raster_plan_io.h"
#include "platform/wgs84.h"

namespace floorpose::platform {
namespace {

constexpr size_t kMaxPlanBytes = 256u << 20;  // larger files are not floor plans
constexpr const char* kPlanExtensions[] = {".geojson", ".json", ".txt", ".yaml", ".floors"};
constexpr size_t kMaxFloorSetBytes = 1u << 20;

bool ValidPlanId(const std::string& id) {
  if (id.empty() || id.size() > 128 || id[0] == '.') return false;
  for (char c : id)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.')
      return false;
  return true;
}

using Json = nlohmann::json;

bool ToPoint(const Json& j, Eigen::Vector2d* p) {
  if (!j.is_array() || j.size() < 2 || !j[0].is_number() || !j[1].is_number()) return false;
  *p = {j[0].get<double>(), j[1].get<double>()};
  return true;
}

// Appends the segments of a line string (or ring); false if it is not one.
bool AddLine(const Json& coords, std::vector<Segment>* out) {
  if (!coords.is_array()) return false;
  Eigen::Vector2d prev = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < coords.size(); ++i) {
    Eigen::Vector2d p;
    if (!ToPoint(coords[i], &p)) return false;
    if (i > 0) out->push_back({prev, p});
    prev = p;
  }
  return true;
}

// Returns an error or empty; ignores geometry types that carry no walls (points).
std::string AddGeometry(const Json& g, std::vector<Segment>* out, int depth) {
  if (depth > 8) return "geometry nested too deep";
  if (!g.is_object() || !g.contains("type") || !g["type"].is_string())
    return "geometry without a type";
  const std::string type = g["type"];
  if (type == "GeometryCollection") {
    if (!g.contains("geometries") || !g["geometries"].is_array())
      return "GeometryCollection without geometries";
    for (const Json& sub : g["geometries"]) {
      std::string e = AddGeometry(sub, out, depth + 1);
      if (!e.empty()) return e;
    }
    return {};
  }
  if (type == "Point" || type == "MultiPoint") return {};
  if (!g.contains("coordinates")) return type + " without coordinates";
  const Json& c = g["coordinates"];
  bool ok = c.is_array();
  if (type == "LineString") {
    ok = ok && AddLine(c, out);
  } else if (type == "MultiLineString" || type == "Polygon") {
    for (size_t i = 0; ok && i < c.size(); ++i) ok = AddLine(c[i], out);
  } else if (type == "MultiPolygon") {
    for (size_t i = 0; ok && i < c.size(); ++i) {
      ok = c[i].is_array();
      for (size_t k = 0; ok && k < c[i].size(); ++k) ok = AddLine(c[i][k], out);
    }
  } else {
    return "unsupported geometry type " + type;
  }
  return ok ? std::string() : "bad coordinates in a " + type;
}

// A GeoJSON in longitude/latitude (RFC 7946) has no `crs` member or names CRS84 / EPSG:4326
// in it, does not say `"units": "m"`, and has coordinates that can be longitude/latitude
// of one building. Anything else is metres in a local frame, as written.
// The bounding box of the finite end points; empty (min > max) when there are none.
std::pair<Eigen::Vector2d, Eigen::Vector2d> FiniteBounds(const std::vector<Segment>& raw) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300), hi = -lo;
  for (const Segment& s : raw)
    for (const Eigen::Vector2d& p : {s.a, s.b})
      if (p.allFinite()) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  return {lo, hi};
}

bool IsLonLat(const Json& doc, const std::vector<Segment>& raw) {
  if (doc.contains("properties") && doc["properties"].is_object() &&
      doc["properties"].contains("units") && doc["properties"]["units"] == "m")
    return false;
  if (doc.contains("crs")) {
    const std::string crs = doc["crs"].dump();
    if (crs.find("CRS84") == std::string::npos && crs.find("4326") == std::string::npos)
      return false;
  }
  const auto [lo, hi] = FiniteBounds(raw);
  return (hi - lo).minCoeff() >= 0 && CouldBeLonLat(lo, hi);
}

// Projects `raw` from longitude/latitude to metres about `properties.origin` ([lon, lat])
// or else the south-west corner of the bounding box. Returns an error or empty; `frame`
// says the projection and origin.
std::string ProjectLonLat(const Json& doc, std::vector<Segment>* raw, std::string* frame,
                          Georeference* georeference) {
  Eigen::Vector2d origin = FiniteBounds(*raw).first;
  const char* which = "the south-west corner of its bounding box";
  if (doc.contains("properties") && doc["properties"].is_object() &&
      doc["properties"].contains("origin")) {
    if (!ToPoint(doc["properties"]["origin"], &origin) || std::abs(origin.x()) > 180 ||
        std::abs(origin.y()) > 90)
      return "properties.origin is not [longitude, latitude]";
    which = "properties.origin";
  }
  // Non-finite points stay as they are: MakeFloorPlan drops their segments and counts them.
  std::vector<Eigen::Vector2d> points;
  for (const Segment& s : *raw)
    for (const Eigen::Vector2d& p : {s.a, s.b})
      if (p.allFinite()) points.push_back(p);
  std::string error;
  if (!ProjectToLocalMetres(origin, &points, &error)) return error;
  size_t next = 0;
  for (Segment& s : *raw)
    for (Eigen::Vector2d* p : {&s.a, &s.b})
      if (p->allFinite()) *p = points[next++];
  char text[200];
  std::snprintf(text, sizeof(text),
                "WGS84 longitude/latitude, projected to local metres (azimuthal equidistant, "
                "origin %.7f, %.7f: %s)",
                origin.x(), origin.y(), which);
  *frame = text;
  georeference->origin_lon_lat = origin;
  georeference->rotation_rad = 0.0;
  return {};
}

// A local plan's `properties.georeference`: {"origin": [lon, lat], "rotation_deg": a}, the
// plan's +x axis a degrees counter-clockwise from east (0 when missing). Returns an error
// or empty; nothing when the plan has none.
std::string ReadGeoreference(const Json& doc, std::optional<Georeference>* out) {
  if (!doc.contains("properties") || !doc["properties"].is_object() ||
      !doc["properties"].contains("georeference"))
    return {};
  const Json& g = doc["properties"]["georeference"];
  Georeference r;
  if (!g.is_object() || !g.contains("origin") || !ToPoint(g["origin"], &r.origin_lon_lat) ||
      std::abs(r.origin_lon_lat.x()) > 180 || std::abs(r.origin_lon_lat.y()) > 90)
    return "properties.georeference.origin is not [longitude, latitude]";
  if (g.contains("rotation_deg")) {
    if (!g["rotation_deg"].is_number() || !std::isfinite(g["rotation_deg"].get<double>()))
      return "properties.georeference.rotation_deg is not a number";
    r.rotation_rad = g["rotation_deg"].get<double>() * M_PI / 180.0;
  }
  *out = r;
  return {};
}

// Every line of a GeoJSON document as read, and what it belongs to: a LineKind, or the
// room of that index (kRoomTag - index) for the outline of a room or unit.
struct TaggedLines {
  static constexpr int kRoomTag = -1;
  std::vector<Segment> raw;
  std::vector<int> tags;
  std::vector<std::string> room_names;

  // One feature's lines. properties.kind says what they are (core/floor_plan.h, LineKind):
  // walls when it says nothing; a room or unit is an outline with a name; other features
  // (labels, furniture) carry no lines of the plan. Returns an error or empty.
  std::string AddFeature(const Json& f) {
    if (!f.is_object()) return "feature is not an object";
    if (!f.contains("geometry") || f["geometry"].is_null()) return {};
    int tag = static_cast<int>(LineKind::kWall);
    const Json* props =
        f.contains("properties") && f["properties"].is_object() ? &f["properties"] : nullptr;
    if (props && props->contains("kind") && (*props)["kind"].is_string()) {
      const std::string kind = (*props)["kind"];
      LineKind k;
      if (kind == "room" || kind == "unit") {
        tag = kRoomTag - static_cast<int>(room_names.size());
        const bool named = props->contains("name") && (*props)["name"].is_string();
        room_names.push_back(named ? (*props)["name"].get<std::string>() : std::string());
      } else if (ParseLineKind(kind, &k)) {
        tag = static_cast<int>(k);
      } else {
        return {};
      }
    }
    const size_t before = raw.size();
    std::string e = AddGeometry(f["geometry"], &raw, 0);
    tags.resize(raw.size(), tag);
    if (tag <= kRoomTag && raw.size() == before) room_names.pop_back();
    return e;
  }

  // A FeatureCollection, a Feature or a bare geometry (walls). Returns an error or empty.
  std::string AddDocument(const Json& doc) {
    if (!doc.is_object() || !doc.contains("type") || !doc["type"].is_string())
      return "top level is not a GeoJSON object";
    if (doc["type"] == "FeatureCollection") {
      if (!doc.contains("features") || !doc["features"].is_array())
        return "FeatureCollection without features";
      for (size_t i = 0; i < doc["features"].size(); ++i)
        if (const std::string e = AddFeature(doc["features"][i]); !e.empty())
          return "feature " + std::to_string(i) + ": " + e;
      return {};
    }
    if (doc["type"] == "Feature") return AddFeature(doc);
    std::string e = AddGeometry(doc, &raw, 0);
    tags.resize(raw.size(), static_cast<int>(LineKind::kWall));
    return e;
  }

  // The plan's lines and rooms (each outline its segments' points in order).
  void Split(std::vector<PlanLine>* lines, std::vector<PlanRoom>* rooms) {
    rooms->assign(room_names.size(), {});
    for (size_t i = 0; i < raw.size(); ++i) {
      if (tags[i] >= 0) {
        lines->push_back({raw[i], static_cast<LineKind>(tags[i])});
        continue;
      }
      PlanRoom& room = (*rooms)[static_cast<size_t>(kRoomTag - tags[i])];
      if (room.outline.empty()) room.outline.push_back(raw[i].a);
      room.outline.push_back(raw[i].b);
    }
    for (size_t i = 0; i < rooms->size(); ++i) (*rooms)[i].name = std::move(room_names[i]);
  }
};

}  // namespace

bool ReadFile(const std::string& path, size_t max_bytes, std::string* contents,
              std::string* error) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    *error = path + ": not a readable file";
    return false;
  }
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) {
    *error = path + ": " + ec.message();
    return false;
  }
  if (size > max_bytes) {
    *error = path + ": " + std::to_string(size) + " bytes, over the limit of " +
             std::to_string(max_bytes);
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = path + ": " + std::strerror(errno);
    return false;
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  *contents = ss.str();
  return true;
}

FloorPlanParse ParseGeoJsonFloorPlan(std::string_view text, std::string id) {
  FloorPlanParse out;
  const Json doc = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (doc.is_discarded()) {
    out.error = "GeoJSON: not valid JSON";
    return out;
  }
  TaggedLines read;
  std::string error = read.AddDocument(doc);
  std::string frame;
  std::optional<Georeference> georeference;
  if (error.empty() && IsLonLat(doc, read.raw)) {
    georeference.emplace();
    error = ProjectLonLat(doc, &read.raw, &frame, &*georeference);
  } else if (error.empty()) {
    error = ReadGeoreference(doc, &georeference);
  }
  if (!error.empty()) {
    out.error = "GeoJSON: " + error;
    return out;
  }
  std::vector<PlanLine> lines;
  std::vector<PlanRoom> rooms;
  read.Split(&lines, &rooms);
  out = MakeFloorPlan(std::move(id), lines, std::move(rooms));
  out.frame = std::move(frame);
  if (out.ok()) out.georeference = georeference;
  return out;
}

std::string ToGeoJson(const FloorPlan& plan, const std::string& source) {
  // One feature a line: diffable, and small enough to read.
  const nlohmann::ordered_json properties = {{"units", "m"}, {"source", source}};
  std::string out = "{\"type\": \"FeatureCollection\", \"properties\": " +
                    properties.dump(-1, ' ', false, Json::error_handler_t::replace) +
                    ", \"features\": [\n";
  auto round = [](double v) { return std::round(v * 1e4) / 1e4; };  // 0.1 mm
  auto point = [&](const Eigen::Vector2d& p) { return Json::array({round(p.x()), round(p.y())}); };
  std::vector<std::string> features;
  auto line = [&](const Segment& s, LineKind kind) {
    const nlohmann::ordered_json f = {
        {"type", "Feature"},
        {"properties", {{"kind", LineKindName(kind)}}},
        {"geometry", {{"type", "LineString"}, {"coordinates", {point(s.a), point(s.b)}}}}};
    features.push_back(f.dump());
  };
  for (size_t i = 0; i < plan.segments.size(); ++i) line(plan.segments[i], plan.KindOf(i));
  for (const PlanLine& o : plan.openings) line(o.segment, o.kind);
  for (const PlanRoom& room : plan.rooms) {
    Json ring = Json::array();
    for (const Eigen::Vector2d& p : room.outline) ring.push_back(point(p));
    const nlohmann::ordered_json f = {
        {"type", "Feature"},
        {"properties", {{"kind", "room"}, {"name", room.name}}},
        {"geometry", {{"type", "Polygon"}, {"coordinates", Json::array({ring})}}}};
    features.push_back(f.dump(-1, ' ', false, Json::error_handler_t::replace));
  }
  for (size_t i = 0; i < features.size(); ++i)
    out += features[i] + (i + 1 < features.size() ? ",\n" : "\n");
  return out + "]}\n";
}

FloorPlanParse LoadFloorPlan(const std::string& path) {
  const std::filesystem::path p(path);
  const std::string ext = p.extension().string();
  if (ext == ".yaml" || ext == ".yml") return LoadRasterFloorPlan(path);
  FloorPlanParse out;
  std::string text;
  if (!ReadFile(path, kMaxPlanBytes, &text, &out.error)) return out;
  const std::string id = p.stem().string();
  if (ext == ".geojson" || ext == ".json") {
    out = ParseGeoJsonFloorPlan(text, id);
  } else if (ext == ".txt") {
    out = ParseTextFloorPlan(text, id);
  } else {
    out.error = "unknown floor plan format '" + ext + "' (expected .geojson, .txt or .yaml)";
  }
  if (!out.ok()) out.error = path + ": " + out.error;
  return out;
}

const FloorEntry* FloorSet::Find(const std::string& id) const {
  for (const FloorEntry& f : floors)
    if (f.id == id) return &f;
  return nullptr;
}

const FloorEntry& FloorSet::Nearest(double height_m) const {
  return *std::min_element(floors.begin(), floors.end(), [&](const auto& a, const auto& b) {
    return std::abs(a.height_m - height_m) < std::abs(b.height_m - height_m);
  });
}

bool IsFloorSet(const std::string& path) {
  return std::filesystem::path(path).extension() == ".floors";
}

FloorSet LoadFloorSet(const std::string& path) {
  FloorSet out;
  std::string text;
  if (!ReadFile(path, kMaxFloorSetBytes, &text, &out.error)) return out;
  return ParseFloorSet(text, std::filesystem::path(path).parent_path().string(), path);
}

FloorSet ParseFloorSet(std::string_view text, const std::string& dir, const std::string& name) {
  FloorSet out;
  std::istringstream in{std::string(text)};
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    line = line.substr(0, line.find('#'));
    std::istringstream fields(line);
    FloorEntry f;
    std::string height, rest;
    if (!(fields >> f.id)) continue;  // blank or comment
    const std::string where = name + ":" + std::to_string(number) + ": ";
    char* end = nullptr;
    if (fields >> height) f.height_m = std::strtod(height.c_str(), &end);
    if (!end || *end != '\0' || !(fields >> f.plan_path) || (fields >> rest)) {
      out.error = where + "expected '<floor id> <height m> <plan file>'";
      return out;
    }
    if (!std::isfinite(f.height_m)) {
      out.error = where + "height '" + height + "' is not a number";
      return out;
    }
    if (out.Find(f.id)) {
      out.error = where + "floor '" + f.id + "' twice";
      return out;
    }
    for (const FloorEntry& other : out.floors)
      if (std::abs(other.height_m - f.height_m) < 1.0) {
        out.error =
            where + "floor '" + f.id + "' within 1 m of the height of floor '" + other.id + "'";
        return out;
      }
    if (std::filesystem::path(f.plan_path).is_relative() && !dir.empty())
      f.plan_path = (std::filesystem::path(dir) / f.plan_path).string();
    out.floors.push_back(std::move(f));
  }
  if (out.floors.empty()) out.error = name + ": no floors";
  return out;
}

std::vector<std::string> ListPlanIds(const std::string& dir) {
  std::vector<std::string> ids;
  std::error_code ec;
  if (dir.empty()) return ids;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::filesystem::path& p = entry.path();
    const std::string ext = p.extension().string();
    if (!entry.is_regular_file(ec) || !ValidPlanId(p.stem().string())) continue;
    if (std::find(std::begin(kPlanExtensions), std::end(kPlanExtensions), ext) !=
        std::end(kPlanExtensions))
      ids.push_back(p.stem().string());
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

bool FindPlanFile(const std::string& dir, const std::string& id, std::string* path,
                  std::string* error) {
  if (!ValidPlanId(id)) {
    *error = "invalid plan id '" + id.substr(0, 64) + "' (letters, digits, '-', '_', '.')";
    return false;
  }
  if (dir.empty()) {
    *error = "no plan directory configured (plan_dir)";
    return false;
  }
  std::error_code ec;
  for (const char* ext : kPlanExtensions) {
    const std::filesystem::path p = std::filesystem::path(dir) / (id + ext);
    if (std::filesystem::is_regular_file(p, ec)) {
      *path = p.string();
      return true;
    }
  }
  *error = "no plan '" + id + "' in " + dir;
  return false;
}

}  // namespace floorpose::platform
