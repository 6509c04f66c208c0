// `floorpose import` on a DXF that GDAL writes here: walls on one CAD layer, furniture on
// another, drawn in millimetres ($INSUNITS 4).
#include "tools/lib/plan_import.h"

#include <cpl_vsi.h>
#include "tools/lib/building_import.h"

#include <cpl_conv.h>
#include <gdal.h>
#include <ogr_api.h>

#include "platform/floor_plan_io.h"
#include "tests/test_util.h"

namespace floorpose::tools {
namespace {

class PlanImportTest : public testing::TempDirTest {
 protected:
  // GDAL's DXF writer copies a header template; ours says millimetres (or `code`).
  std::string MillimetreHeader(const char* code = "     4") {
    GDALAllRegister();
    const char* stock = CPLFindFile("gdal", "header.dxf");
    EXPECT_NE(stock, nullptr) << "GDAL's header.dxf template not found";
    std::string header = testing::ReadText(stock ? stock : "");
    const size_t at = header.find("$INSUNITS");
    EXPECT_NE(at, std::string::npos);
    // "$INSUNITS\n 70\n     1\n": the value is the third line.
    size_t value = header.find('\n', header.find('\n', at) + 1) + 1;
    header.replace(value, header.find('\n', value) - value, code);
    return Write("header_mm.dxf", header);
  }

  std::string WriteDxf(
      const std::string& name,
      const std::vector<std::pair<std::string, std::vector<Eigen::Vector2d>>>& polylines,
      const char* insunits = "     4") {
    GDALAllRegister();
    const std::string header = "HEADER=" + MillimetreHeader(insunits);
    const char* options[] = {header.c_str(), nullptr};
    GDALDatasetH ds = GDALCreate(GDALGetDriverByName("DXF"), Path(name).c_str(), 0, 0, 0,
                                 GDT_Unknown, const_cast<char**>(options));
    EXPECT_NE(ds, nullptr);
    OGRLayerH layer = GDALDatasetCreateLayer(ds, "entities", nullptr, wkbUnknown, nullptr);
    for (const auto& [cad_layer, points] : polylines) {
      OGRFeatureH f = OGR_F_Create(OGR_L_GetLayerDefn(layer));
      OGR_F_SetFieldString(f, OGR_F_GetFieldIndex(f, "Layer"), cad_layer.c_str());
      OGRGeometryH line = OGR_G_CreateGeometry(wkbLineString);
      for (const Eigen::Vector2d& p : points) OGR_G_AddPoint_2D(line, p.x(), p.y());
      OGR_F_SetGeometryDirectly(f, line);
      EXPECT_EQ(OGR_L_CreateFeature(layer, f), OGRERR_NONE);
      OGR_F_Destroy(f);
    }
    GDALClose(ds);
    return Path(name);
  }
};

TEST_F(PlanImportTest, KeepsOnlyTheWallLayerInMetres) {
  const std::string dxf =
      WriteDxf("plan.dxf", {{"WALLS", {{0, 0}, {8000, 0}, {8000, 5000}}},  // two segments
                            {"WALLS", {{0, 0}, {0, 5000}}},                //
                            {"WALLS", {{0, 5000}, {0, 0}}},                // duplicate, reversed
                            {"WALLS", {{3000, 3000}, {3000, 3000}}},       // zero length
                            {"FURNITURE", {{1000, 1000}, {2000, 1000}, {2000, 1600}}}});
  PlanImportOptions options;
  options.layers = {"WALLS"};
  FloorPlan plan;
  PlanImportReport report;
  std::string error;
  ASSERT_TRUE(ImportPlan(dxf, options, &plan, &report, &error)) << error;
  EXPECT_THAT(report.units, ::testing::HasSubstr("$INSUNITS 4"));
  EXPECT_DOUBLE_EQ(report.scale, 0.001);
  EXPECT_THAT(report.layers_seen, ::testing::ElementsAre("FURNITURE", "WALLS"));
  ASSERT_EQ(plan.segments.size(), 3u);
  EXPECT_EQ(report.dropped, 2u);
  EXPECT_EQ(report.skipped_features, 1u);  // the furniture
  EXPECT_NEAR(plan.max.x(), 8.0, 1e-9);
  EXPECT_NEAR(plan.max.y(), 5.0, 1e-9);

  // Written as GeoJSON, it loads as the same plan.
  const std::string out = Write("plan.geojson", platform::ToGeoJson(plan, "test"));
  const FloorPlanParse loaded = platform::LoadFloorPlan(out);
  ASSERT_TRUE(loaded.ok()) << loaded.error;
  ASSERT_EQ(loaded.plan.segments.size(), 3u);
  EXPECT_TRUE(loaded.plan.segments[1].b.isApprox(Eigen::Vector2d(8.0, 5.0)));

  // Without a layer choice the furniture comes too; --units overrides the file.
  options.layers.clear();
  options.units = "cm";
  ASSERT_TRUE(ImportPlan(dxf, options, &plan, &report, &error)) << error;
  EXPECT_EQ(plan.segments.size(), 5u);
  EXPECT_NEAR(plan.max.x(), 80.0, 1e-9);
}

TEST_F(PlanImportTest, BrokenFilesFailClearly) {
  FloorPlan plan;
  PlanImportReport report;
  std::string error;
  EXPECT_FALSE(ImportPlan(Write("junk.dxf", "0\nSECTION\n2\nHEADER\nnot a dxf"), {}, &plan, &report,
                          &error));
  EXPECT_THAT(error, ::testing::HasSubstr("junk.dxf"));
  EXPECT_FALSE(ImportPlan(Path("missing.gpkg"), {}, &plan, &report, &error));
  EXPECT_THAT(error, ::testing::HasSubstr("not a vector file"));

  const std::string dxf = WriteDxf("plan.dxf", {{"WALLS", {{0, 0}, {1000, 0}}}});
  PlanImportOptions options;
  options.layers = {"A-WALL"};
  EXPECT_FALSE(ImportPlan(dxf, options, &plan, &report, &error));
  EXPECT_THAT(error, ::testing::HasSubstr("no layer 'A-WALL' (layers: WALLS)"));
  const std::string furniture = WriteDxf("furniture.dxf", {{"F", {{0, 0}, {0, 0}}}});
  EXPECT_FALSE(ImportPlan(furniture, {}, &plan, &report, &error));
  EXPECT_THAT(error, ::testing::HasSubstr("no usable wall segments"));
}

// A CAD plan drawn to the AIA layer names imports each layer as its kind without a map;
// a map names other layers.
TEST_F(PlanImportTest, AiaLayersBecomeTheirKinds) {
  // 10 x 6 m in millimetres: the south wall drawn whole with a door on it, glass on the
  // north wall's middle third, furniture that stays out.
  const std::string dxf =
      WriteDxf("aia.dxf", {{"A-WALL", {{0, 0}, {10000, 0}, {10000, 6000}, {7000, 6000}}},
                           {"A-WALL", {{3000, 6000}, {0, 6000}, {0, 0}}},
                           {"A-DOOR", {{4000, 0}, {5000, 0}}},
                           {"A-GLAZ", {{3000, 6000}, {7000, 6000}}},
                           {"A-FURN", {{1000, 1000}, {2000, 1000}}}});
  FloorPlan plan;
  PlanImportReport report;
  std::string error;
  ASSERT_TRUE(ImportPlan(dxf, {}, &plan, &report, &error)) << error;
  EXPECT_EQ(report.kept["wall"], 6u);  // 4 drawn, the south wall cut in two by the door
  EXPECT_EQ(report.kept["door"], 1u);
  EXPECT_EQ(report.kept["glass"], 1u);
  EXPECT_EQ(report.skipped_features, 1u);  // the furniture
  ASSERT_EQ(plan.openings.size(), 1u);
  EXPECT_NEAR(plan.openings[0].segment.Length(), 1.0, 1e-9);
  EXPECT_NEAR(plan.max.x(), 10.0, 1e-9);

  PlanImportOptions mapped;
  mapped.layer_map = {{LineKind::kWall, "A-WALL"}, {LineKind::kWindow, "A-GLAZ"}};
  ASSERT_TRUE(ImportPlan(dxf, mapped, &plan, &report, &error)) << error;
  EXPECT_EQ(report.kept["window"], 1u);
  EXPECT_EQ(report.kept.count("door"), 0u);
}

// A plan in millimetres whose file does not say so is refused with the --units that fits,
// not read as a building 10 km across.
TEST_F(PlanImportTest, AMillimetrePlanWithoutUnitsIsRefusedWithTheHint) {
  const std::string dxf = WriteDxf(
      "mm.dxf", {{"A-WALL", {{0, 0}, {42000, 0}, {42000, 18000}, {0, 18000}, {0, 0}}}}, "     0");
  FloorPlan plan;
  PlanImportReport report;
  std::string error;
  EXPECT_FALSE(ImportPlan(dxf, {}, &plan, &report, &error));
  EXPECT_THAT(error, ::testing::HasSubstr("42000 m across"));
  EXPECT_THAT(error, ::testing::HasSubstr("--units mm"));
  EXPECT_THAT(error, ::testing::HasSubstr("42.0 m across"));
  PlanImportOptions options;
  options.units = "mm";
  ASSERT_TRUE(ImportPlan(dxf, options, &plan, &report, &error)) << error;
  EXPECT_NEAR(plan.max.x(), 42.0, 1e-9);
}

// An IMDF archive as a venue publishes it (a zip written here through GDAL's /vsizip/):
// two levels, units with names, a stairwell, openings (one an emergency exit) and a
// fixture, in longitude/latitude. It imports to a .floors set in metres, one frame.
TEST_F(PlanImportTest, ImdfArchiveImportsToAFloorsSet) {
  // Degrees per metre near 49.4 N (Heidelberg): a 20 x 10 m building.
  const double lon0 = 8.675, lat0 = 49.418, dlon = 1.0 / 72560.0, dlat = 1.0 / 111210.0;
  auto pt = [&](double x, double y) {
    return "[" + std::to_string(lon0 + x * dlon) + "," + std::to_string(lat0 + y * dlat) + "]";
  };
  auto box = [&](double x0, double y0, double x1, double y1) {
    return R"({"type":"Polygon","coordinates":[[)" + pt(x0, y0) + "," + pt(x1, y0) + "," +
           pt(x1, y1) + "," + pt(x0, y1) + "," + pt(x0, y0) + "]]}";
  };
  auto line = [&](double x0, double y0, double x1, double y1) {
    return R"({"type":"LineString","coordinates":[)" + pt(x0, y0) + "," + pt(x1, y1) + "]}";
  };
  auto feature = [](const std::string& id, const std::string& props, const std::string& g) {
    return R"({"type":"Feature","id":")" + id + R"(","feature_type":"x","properties":)" + props +
           R"(,"geometry":)" + g + "}";
  };
  auto collection = [](const std::vector<std::string>& fs) {
    std::string out = R"({"type":"FeatureCollection","features":[)";
    for (size_t i = 0; i < fs.size(); ++i) out += (i ? "," : "") + fs[i];
    return out + "]}";
  };
  const std::string level = collection(
      {feature("l0", R"({"ordinal":0,"short_name":{"en":"EG"},"category":"unspecified"})",
               box(0, 0, 20, 10)),
       feature("l1", R"({"ordinal":1,"short_name":{"en":"OG1"},"category":"unspecified"})",
               box(0, 0, 20, 10))});
  const std::string unit = collection(
      {feature("u1", R"({"category":"room","level_id":"l0","name":{"en":"Lab \"A\""}})",
               box(0, 0, 10, 10)),
       feature("u2", R"({"category":"room","level_id":"l0","name":{"de":"Flur"}})",
               box(10, 0, 20, 10)),
       feature("u3", R"({"category":"stairs","level_id":"l1","name":null})", box(0, 0, 4, 4)),
       feature("u4", R"({"category":"room","level_id":"l1","name":{"en":"Office"}})",
               box(4, 0, 20, 10))});
  const std::string opening = collection(
      {feature("o1", R"({"category":"pedestrian","level_id":"l0"})", line(10, 4, 10, 5)),
       feature("o2", R"({"category":"emergencyexit","level_id":"l0"})", line(20, 2, 20, 3.2))});
  const std::string fixture =
      collection({feature("f1", R"({"category":"furniture","level_id":"l1"})", box(12, 4, 14, 6))});
  const std::string zip = Path("venue.imdf.zip");
  for (const auto& [name, text] : {std::pair{"level.geojson", level},
                                   {"unit.geojson", unit},
                                   {"opening.geojson", opening},
                                   {"fixture.geojson", fixture}}) {
    VSILFILE* f = VSIFOpenL(("/vsizip/" + zip + "/" + name).c_str(), "wb");
    ASSERT_NE(f, nullptr);
    ASSERT_EQ(VSIFWriteL(text.data(), 1, text.size(), f), text.size());
    VSIFCloseL(f);
  }
  ASSERT_TRUE(IsImdf(zip));
  std::vector<ImportedLevel> levels;
  BuildingImportReport report;
  std::string error;
  ASSERT_TRUE(ImportImdf(zip, 3.5, &levels, &report, &error)) << error;
  ASSERT_EQ(levels.size(), 2u);
  EXPECT_EQ(levels[0].id, "EG");
  EXPECT_EQ(levels[1].id, "OG1");
  EXPECT_DOUBLE_EQ(levels[1].height_m, 3.5);
  // Ground: two rooms' outlines (their shared wall once), a door cutting it, an exit
  // cutting the east wall.
  EXPECT_EQ(report.kept["EG"]["door"], 1u);
  EXPECT_EQ(report.kept["EG"]["exit"], 1u);
  EXPECT_EQ(report.kept["EG"]["room"], 2u);
  EXPECT_EQ(report.kept["EG"]["wall"], 9u);  // 8 edges, two of them cut in two; one shared
  EXPECT_EQ(report.kept["OG1"]["stairs"], 4u);
  EXPECT_EQ(report.kept["OG1"]["room"], 1u);  // the stairs have no name
  EXPECT_EQ(report.kept["OG1"]["wall"], 8u);  // the office and the fixture
  const FloorPlan& ground = levels[0].plan;
  EXPECT_NEAR(ground.max.x() - ground.min.x(), 20.0, 0.05);  // metres, not degrees
  EXPECT_NEAR(ground.max.y() - ground.min.y(), 10.0, 0.05);
  EXPECT_NEAR(ground.min.x(), 0.0, 0.05);  // about the building's south-west corner
  EXPECT_NEAR(levels[1].plan.min.x(), 0.0, 0.05);
  EXPECT_EQ(ground.rooms[0].name, "Lab \"A\"");

  // As a .floors set floorposed loads.
  const std::string floors = Path("venue.floors");
  ASSERT_TRUE(WriteLevels(levels, floors, "test", &error)) << error;
  const platform::FloorSet set = platform::LoadFloorSet(floors);
  ASSERT_TRUE(set.ok()) << set.error;
  ASSERT_EQ(set.floors.size(), 2u);
  EXPECT_DOUBLE_EQ(set.floors[1].height_m, 3.5);
  const FloorPlanParse again = platform::LoadFloorPlan(set.floors[0].plan_path);
  ASSERT_TRUE(again.ok()) << again.error;
  EXPECT_EQ(again.plan.openings.size(), 2u);
  EXPECT_EQ(again.plan.rooms.size(), 2u);
}

// OSM's Simple Indoor Tagging: a room with a door node and a window node on its outline,
// a wall way, on level 0.
TEST_F(PlanImportTest, OsmIndoorImportsDoorsAndWindows) {
  const double lon0 = 8.675, lat0 = 49.418, dlon = 1.0 / 72560.0, dlat = 1.0 / 111210.0;
  std::string osm = R"(<?xml version="1.0" encoding="UTF-8"?>
<osm version="0.6" generator="test">
)";
  auto node = [&](int id, double x, double y, const std::string& tags = "") {
    osm += "<node id=\"" + std::to_string(id) + "\" version=\"1\" lat=\"" +
           std::to_string(lat0 + y * dlat) + "\" lon=\"" + std::to_string(lon0 + x * dlon) + "\"" +
           (tags.empty() ? "/>\n" : ">" + tags + "</node>\n");
  };
  node(1, 0, 0);
  node(2, 8, 0);
  node(3, 8, 6);
  node(4, 0, 6);
  node(5, 4, 0, R"(<tag k="door" v="hinged"/><tag k="level" v="0"/>)");
  node(6, 8, 3, R"(<tag k="window" v="yes"/><tag k="level" v="0"/>)");
  node(7, 4, 6);
  node(8, 4, 10);
  osm += R"(<way id="10" version="1"><nd ref="1"/><nd ref="5"/><nd ref="2"/><nd ref="6"/>)"
         R"(<nd ref="3"/><nd ref="4"/><nd ref="1"/><tag k="indoor" v="room"/>)"
         R"(<tag k="level" v="0"/><tag k="name" v="Lab"/></way>)"
         "\n"
         R"(<way id="11" version="1"><nd ref="7"/><nd ref="8"/><tag k="indoor" v="wall"/>)"
         R"(<tag k="level" v="0"/></way>)"
         "\n</osm>\n";
  const std::string path = Write("building.osm", osm);
  ASSERT_TRUE(IsOsm(path));
  std::vector<ImportedLevel> levels;
  BuildingImportReport report;
  std::string error;
  ASSERT_TRUE(ImportOsm(path, 3.5, &levels, &report, &error)) << error;
  ASSERT_EQ(levels.size(), 1u);
  const FloorPlan& plan = levels[0].plan;
  ASSERT_EQ(plan.openings.size(), 1u);
  EXPECT_EQ(plan.openings[0].kind, LineKind::kDoor);
  EXPECT_NEAR(plan.openings[0].segment.Length(), 0.9, 0.01);
  size_t windows = 0;
  for (size_t i = 0; i < plan.segments.size(); ++i) windows += plan.KindOf(i) == LineKind::kWindow;
  EXPECT_EQ(windows, 1u);
  EXPECT_EQ(report.kept["0"]["door"], 1u);
  EXPECT_EQ(report.kept["0"]["window"], 1u);
  ASSERT_EQ(plan.rooms.size(), 1u);
  EXPECT_EQ(plan.rooms[0].name, "Lab");
  EXPECT_NEAR(plan.max.y() - plan.min.y(), 10.0, 0.05);
  // The room's outline less the door and the window, and the wall way.
  EXPECT_EQ(report.kept["0"]["wall"], 7u);
}

}  // namespace
}  // namespace floorpose::tools
