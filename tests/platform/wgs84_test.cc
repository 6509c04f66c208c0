// Floor plans in WGS84 longitude/latitude (RFC 7946): projected to local metres about the
// south-west corner (or properties.origin); plans in metres read as written; and (with
// FLOORPOSE_DATA) the real ILC mall floor F1 against its published size and walks.
#include "platform/wgs84.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "platform/floor_plan_io.h"
#include "tests/test_util.h"

namespace floorpose::platform {
namespace {

using ::testing::HasSubstr;

// WGS84 radii of curvature at latitude phi (radians): meridian M and prime vertical N.
constexpr double kA = 6378137.0, kE2 = 6.69437999014e-3;
double MeridianRadius(double phi) {
  return kA * (1 - kE2) / std::pow(1 - kE2 * std::sin(phi) * std::sin(phi), 1.5);
}
double PrimeVerticalRadius(double phi) {
  return kA / std::sqrt(1 - kE2 * std::sin(phi) * std::sin(phi));
}

// A closed square ring of side_m metres with its south-west corner at lon0, lat0, in
// degrees, from the radii of curvature (independent of PROJ).
std::string SquareGeoJson(double lon0, double lat0, double side_m, const std::string& extra = "") {
  const double phi = lat0 * M_PI / 180;
  const double dlat = side_m / MeridianRadius(phi) * 180 / M_PI;
  const double dlon = side_m / (PrimeVerticalRadius(phi) * std::cos(phi)) * 180 / M_PI;
  std::ostringstream g;
  g.precision(12);
  g << R"({"type":"FeatureCollection",)" << extra
    << R"("features":[{"type":"Feature","properties":{},"geometry":{"type":"Polygon",)"
    << R"("coordinates":[[[)" << lon0 << "," << lat0 << "],[" << lon0 + dlon << "," << lat0 << "],["
    << lon0 + dlon << "," << lat0 + dlat << "],[" << lon0 << "," << lat0 + dlat << "],[" << lon0
    << "," << lat0 << "]]]}}]}";
  return g.str();
}

TEST(Wgs84PlanTest, AHundredMetreSquareAtSixtyNorthIsAHundredMetres) {
  const FloorPlanParse parse = ParseGeoJsonFloorPlan(SquareGeoJson(10.0, 60.0, 100.0), "sq");
  ASSERT_TRUE(parse.ok()) << parse.error;
  EXPECT_THAT(parse.frame, HasSubstr("WGS84"));
  EXPECT_THAT(parse.frame, HasSubstr("south-west corner"));
  ASSERT_EQ(parse.plan.segments.size(), 4u);
  // The origin is the south-west corner; the square is 100 m a side, to a centimetre.
  EXPECT_NEAR(parse.plan.min.x(), 0.0, 0.01);
  EXPECT_NEAR(parse.plan.min.y(), 0.0, 0.01);
  EXPECT_NEAR(parse.plan.max.x(), 100.0, 0.01);
  EXPECT_NEAR(parse.plan.max.y(), 100.0, 0.01);
  for (const Segment& s : parse.plan.segments) EXPECT_NEAR(s.Length(), 100.0, 0.01);
}

TEST(Wgs84PlanTest, PropertiesOriginIsTheOrigin) {
  // The origin 50 m west and 50 m south of the square's corner (at 60 N, where a degree
  // of longitude is about 55.8 km).
  const double phi = 60.0 * M_PI / 180;
  const double west = 50.0 / (PrimeVerticalRadius(phi) * std::cos(phi)) * 180 / M_PI;
  const double south = 50.0 / MeridianRadius(phi) * 180 / M_PI;
  std::ostringstream props;
  props.precision(12);
  props << R"("properties":{"origin":[)" << 10.0 - west << "," << 60.0 - south << "]},";
  const FloorPlanParse parse =
      ParseGeoJsonFloorPlan(SquareGeoJson(10.0, 60.0, 100.0, props.str()), "sq");
  ASSERT_TRUE(parse.ok()) << parse.error;
  EXPECT_THAT(parse.frame, HasSubstr("properties.origin"));
  EXPECT_NEAR(parse.plan.min.x(), 50.0, 0.02);
  EXPECT_NEAR(parse.plan.min.y(), 50.0, 0.02);
  EXPECT_NEAR(parse.plan.max.x(), 150.0, 0.02);
  EXPECT_NEAR(parse.plan.max.y(), 150.0, 0.02);

  const FloorPlanParse bad = ParseGeoJsonFloorPlan(
      SquareGeoJson(10.0, 60.0, 100.0, R"("properties":{"origin":[10,"north"]},)"), "sq");
  EXPECT_FALSE(bad.ok());
  EXPECT_THAT(bad.error, HasSubstr("origin"));
}

TEST(Wgs84PlanTest, CrsNamingWgs84IsLonLatAndAnyOtherIsMetres) {
  const FloorPlanParse crs84 = ParseGeoJsonFloorPlan(
      SquareGeoJson(
          10.0, 60.0, 100.0,
          R"("crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:OGC:1.3:CRS84"}},)"),
      "sq");
  ASSERT_TRUE(crs84.ok()) << crs84.error;
  EXPECT_NEAR(crs84.plan.max.x(), 100.0, 0.01);
  const FloorPlanParse other = ParseGeoJsonFloorPlan(
      SquareGeoJson(10.0, 60.0, 100.0,
                    R"("crs":{"type":"name","properties":{"name":"EPSG:25832"}},)"),
      "sq");
  ASSERT_TRUE(other.ok()) << other.error;
  EXPECT_TRUE(other.frame.empty());
  EXPECT_NEAR(other.plan.min.x(), 10.0, 1e-9);
}

TEST(Wgs84PlanTest, APlanInMetresIsReadAsWritten) {
  // Metres that cannot be longitude/latitude (30 m across), and metres that could, but
  // say "units": "m".
  const std::string metres =
      R"({"type":"FeatureCollection","features":[{"type":"Feature","properties":{"kind":"wall"},)"
      R"("geometry":{"type":"LineString","coordinates":[[1.5,-2.0],[31.5,-2.0]]}}]})";
  const FloorPlanParse parse = ParseGeoJsonFloorPlan(metres, "m");
  ASSERT_TRUE(parse.ok()) << parse.error;
  EXPECT_TRUE(parse.frame.empty());
  EXPECT_EQ(parse.plan.segments[0].a, Eigen::Vector2d(1.5, -2.0));
  EXPECT_EQ(parse.plan.segments[0].b, Eigen::Vector2d(31.5, -2.0));

  const FloorPlanParse said = ParseGeoJsonFloorPlan(
      SquareGeoJson(10.0, 60.0, 100.0, R"("properties":{"units":"m"},)"), "sq");
  ASSERT_TRUE(said.ok()) << said.error;
  EXPECT_TRUE(said.frame.empty());
  EXPECT_EQ(said.plan.min, Eigen::Vector2d(10.0, 60.0));
}

// Even-odd over every ring of a (Multi)Polygon: inside the outline, outside its holes.
bool InsideRings(const std::vector<std::vector<Eigen::Vector2d>>& rings, const Eigen::Vector2d& p) {
  bool inside = false;
  for (const auto& ring : rings)
    for (size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++)
      if ((ring[i].y() > p.y()) != (ring[j].y() > p.y()) &&
          p.x() < ring[j].x() + (p.y() - ring[j].y()) / (ring[i].y() - ring[j].y()) *
                                    (ring[i].x() - ring[j].x()))
        inside = !inside;
  return inside;
}

TEST(Wgs84PlanTest, AWgs84PlanIsGeoreferencedAndGoesBackToLonLat) {
  const FloorPlanParse parse = ParseGeoJsonFloorPlan(SquareGeoJson(8.67, 49.41, 100), "sq");
  ASSERT_TRUE(parse.ok()) << parse.error;
  ASSERT_TRUE(parse.georeference.has_value());
  EXPECT_EQ(parse.georeference->origin_lon_lat, Eigen::Vector2d(8.67, 49.41));
  std::vector<Eigen::Vector2d> corner = {{100, 100}};
  std::string error;
  ASSERT_TRUE(PlanToLonLat(*parse.georeference, &corner, &error)) << error;
  const double phi = 49.41 * M_PI / 180;
  EXPECT_NEAR((corner[0].y() - 49.41) * M_PI / 180 * MeridianRadius(phi), 100.0, 0.01);
  EXPECT_NEAR((corner[0].x() - 8.67) * M_PI / 180 * PrimeVerticalRadius(phi) * std::cos(phi), 100.0,
              0.01);
}

TEST(Wgs84PlanTest, ALocalPlanIsGeoreferencedByItsProperties) {
  // The plan's +x points north (90 degrees counter-clockwise from east).
  const FloorPlanParse parse = ParseGeoJsonFloorPlan(
      R"({"type": "FeatureCollection", "properties": {"georeference":
          {"origin": [-122.3, 47.6], "rotation_deg": 90}}, "features": [
        {"type": "Feature", "properties": {}, "geometry": {"type": "LineString",
         "coordinates": [[0, 0], [20, 0]]}}]})",
      "local");
  ASSERT_TRUE(parse.ok()) << parse.error;
  EXPECT_TRUE(parse.frame.empty()) << "coordinates read as written";
  ASSERT_TRUE(parse.georeference.has_value());
  std::vector<Eigen::Vector2d> points = {{0, 0}, {20, 0}};
  std::string error;
  ASSERT_TRUE(PlanToLonLat(*parse.georeference, &points, &error)) << error;
  EXPECT_NEAR(points[0].x(), -122.3, 1e-12);
  EXPECT_NEAR(points[0].y(), 47.6, 1e-12);
  EXPECT_NEAR(points[1].x(), -122.3, 1e-9) << "due north";
  EXPECT_NEAR((points[1].y() - 47.6) * M_PI / 180 * MeridianRadius(47.6 * M_PI / 180), 20.0, 0.001);
  // Without one: none; a bad one: refused.
  EXPECT_FALSE(
      ParseGeoJsonFloorPlan(R"({"type": "LineString", "coordinates": [[0, 0], [20, 0]]})", "bare")
          .georeference.has_value());
  EXPECT_THAT(ParseGeoJsonFloorPlan(R"({"type": "FeatureCollection", "properties":
                  {"georeference": {"origin": [500, 0]}}, "features": []})",
                                    "bad")
                  .error,
              HasSubstr("georeference.origin"));
}

TEST(Wgs84PlanTest, IlcMallFloorF1HasItsPublishedSizeAndItsWalksInside) {
  const auto data = testing::DataDir();
  if (!data) GTEST_SKIP() << testing::kNoDataMessage;
  const std::filesystem::path floor = *data / "ilc" / "site1" / "F1";
  const FloorPlanParse parse = LoadFloorPlan((floor / "geojson_map.json").string());
  ASSERT_TRUE(parse.ok()) << parse.error;
  EXPECT_THAT(parse.frame, HasSubstr("WGS84"));
  const auto info = nlohmann::json::parse(testing::ReadText(floor / "floor_info.json"));
  const double width = info["map_info"]["width"], height = info["map_info"]["height"];
  const Eigen::Vector2d extent = parse.plan.max - parse.plan.min;
  EXPECT_NEAR(extent.x() / width, 1.0, 0.005) << extent.x() << " m against " << width;
  EXPECT_NEAR(extent.y() / height, 1.0, 0.005) << extent.y() << " m against " << height;

  // The outline (feature 0), projected about the same origin as the plan.
  const auto doc = nlohmann::json::parse(testing::ReadText(floor / "geojson_map.json"));
  Eigen::Vector2d origin = Eigen::Vector2d::Constant(1e300);
  std::vector<std::vector<Eigen::Vector2d>> rings;
  for (size_t f = 0; f < doc["features"].size(); ++f) {
    const auto& g = doc["features"][f]["geometry"];
    const auto polygons =
        g["type"] == "Polygon" ? nlohmann::json::array({g["coordinates"]}) : g["coordinates"];
    for (const auto& polygon : polygons)
      for (const auto& ring : polygon) {
        std::vector<Eigen::Vector2d> points;
        for (const auto& c : ring) points.emplace_back(c[0].get<double>(), c[1].get<double>());
        for (const auto& p : points) origin = origin.cwiseMin(p);
        if (f == 0) rings.push_back(points);
      }
  }
  std::string error;
  for (auto& ring : rings) ASSERT_TRUE(ProjectToLocalMetres(origin, &ring, &error)) << error;

  std::istringstream csv(testing::ReadText(floor / "waypoints.csv"));
  std::string line;
  std::getline(csv, line);  // header
  size_t total = 0, inside = 0;
  while (std::getline(csv, line)) {
    std::istringstream fields(line);
    std::string walk, t, x, y;
    ASSERT_TRUE(std::getline(fields, walk, ',') && std::getline(fields, t, ',') &&
                std::getline(fields, x, ',') && std::getline(fields, y, ','))
        << line;
    ++total;
    inside += InsideRings(rings, {std::stod(x), std::stod(y)});
  }
  ASSERT_GT(total, 500u);
  EXPECT_GE(static_cast<double>(inside), 0.97 * static_cast<double>(total))
      << inside << " of " << total << " waypoints inside the outline";
}

}  // namespace
}  // namespace floorpose::platform
