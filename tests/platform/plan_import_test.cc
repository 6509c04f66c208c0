// `floorpose import` on a DXF that GDAL writes here: walls on one CAD layer, furniture on
// another, drawn in millimetres ($INSUNITS 4).
#include "tools/lib/plan_import.h"

#include <cpl_conv.h>
#include <gdal.h>
#include <ogr_api.h>

#include "platform/floor_plan_io.h"
#include "tests/test_util.h"

namespace floorpose::tools {
namespace {

class PlanImportTest : public testing::TempDirTest {
 protected:
  // GDAL's DXF writer copies a header template; ours says millimetres.
  std::string MillimetreHeader() {
    GDALAllRegister();
    const char* stock = CPLFindFile("gdal", "header.dxf");
    EXPECT_NE(stock, nullptr) << "GDAL's header.dxf template not found";
    std::string header = testing::ReadText(stock ? stock : "");
    const size_t at = header.find("$INSUNITS");
    EXPECT_NE(at, std::string::npos);
    // "$INSUNITS\n 70\n     1\n": the value is the third line.
    size_t value = header.find('\n', header.find('\n', at) + 1) + 1;
    header.replace(value, header.find('\n', value) - value, "     4");
    return Write("header_mm.dxf", header);
  }

  std::string WriteDxf(
      const std::string& name,
      const std::vector<std::pair<std::string, std::vector<Eigen::Vector2d>>>& polylines) {
    GDALAllRegister();
    const std::string header = "HEADER=" + MillimetreHeader();
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

}  // namespace
}  // namespace floorpose::tools
