// Floor plan files: GeoJSON geometry kinds, broken documents, loading by extension, and
// (with FLOORPOSE_DATA) every real plan of the developer data set in both formats.
#include "platform/floor_plan_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>

#include "tests/test_util.h"

namespace floorpose::platform {
namespace {

using ::testing::HasSubstr;

// A FeatureCollection around the given features (JSON text).
std::string Collection(const std::string& features) {
  return R"({"type":"FeatureCollection","features":[)" + features + "]}";
}

std::string Feature(const std::string& geometry, const std::string& kind = "wall") {
  return R"({"type":"Feature","properties":{"kind":")" + kind + R"("},"geometry":)" + geometry +
         "}";
}

size_t SegmentCount(const std::string& geojson) {
  const auto parse = ParseGeoJsonFloorPlan(geojson, "t");
  EXPECT_TRUE(parse.ok()) << parse.error << "\n" << geojson;
  return parse.plan.segments.size();
}

// A line string inside `depth` geometry collections.
std::string DeeplyNested(int depth) {
  std::string g = R"({"type":"LineString","coordinates":[[0,0],[1,0]]})";
  for (int i = 0; i < depth; ++i) g = R"({"type":"GeometryCollection","geometries":[)" + g + "]}";
  return g;
}

TEST(GeoJsonTest, LineString) {
  const auto parse = ParseGeoJsonFloorPlan(
      Collection(Feature(R"({"type":"LineString","coordinates":[[0,0],[4,0],[4,3.5]]})")),
      "plan-1");
  ASSERT_TRUE(parse.ok()) << parse.error;
  EXPECT_EQ(parse.plan.id, "plan-1");
  ASSERT_EQ(parse.plan.segments.size(), 2u);
  EXPECT_EQ(parse.plan.segments[1].a, Eigen::Vector2d(4, 0));
  EXPECT_EQ(parse.plan.segments[1].b, Eigen::Vector2d(4, 3.5));
  EXPECT_EQ(parse.plan.max, Eigen::Vector2d(4, 3.5));
}

TEST(GeoJsonTest, GeometryKinds) {
  EXPECT_EQ(
      SegmentCount(Collection(Feature(
          R"({"type":"MultiLineString","coordinates":[[[0,0],[1,0]],[[0,1],[1,1],[2,1]]]})"))),
      3u);
  // A closed ring of 5 positions is 4 walls; a hole adds its own.
  const std::string square = "[[0,0],[4,0],[4,4],[0,4],[0,0]]";
  const std::string hole = "[[1,1],[2,1],[2,2],[1,1]]";
  EXPECT_EQ(SegmentCount(Collection(
                Feature(R"({"type":"Polygon","coordinates":[)" + square + "," + hole + "]}"))),
            7u);
  EXPECT_EQ(SegmentCount(Collection(Feature(R"({"type":"MultiPolygon","coordinates":[[)" + square +
                                            "],[" + hole + "]]}"))),
            7u);
  // Geometry collections, a bare Feature and a bare geometry are accepted too.
  EXPECT_EQ(
      SegmentCount(Feature(
          R"({"type":"GeometryCollection","geometries":[{"type":"LineString","coordinates":[[0,0],[1,0]]},{"type":"Point","coordinates":[5,5]}]})")),
      1u);
  EXPECT_EQ(SegmentCount(R"({"type":"LineString","coordinates":[[0,0],[0,2]]})"), 1u);
  // Nesting up to the limit is fine.
  EXPECT_EQ(SegmentCount(DeeplyNested(8)), 1u);
  // Extra dimensions (altitude) are ignored.
  EXPECT_EQ(SegmentCount(R"({"type":"LineString","coordinates":[[0,0,3],[0,2,3]]})"), 1u);
}

TEST(GeoJsonTest, ADoorOnAWallIsAGapAndPointsAreSkipped) {
  const std::string wall = Feature(R"({"type":"LineString","coordinates":[[0,0],[4,0]]})");
  const std::string door = Feature(R"({"type":"LineString","coordinates":[[1,0],[2,0]]})", "door");
  const std::string door_point = Feature(R"({"type":"Point","coordinates":[1.5,0]})", "door");
  const std::string point = Feature(R"({"type":"Point","coordinates":[9,9]})");
  const std::string label =
      Feature(R"({"type":"LineString","coordinates":[[0,9],[9,9]]})", "label");
  const std::string no_geometry = R"({"type":"Feature","properties":{},"geometry":null})";
  const auto parse = ParseGeoJsonFloorPlan(Collection(wall + "," + door + "," + door_point + "," +
                                                      point + "," + label + "," + no_geometry),
                                           "t");
  ASSERT_TRUE(parse.ok()) << parse.error;
  // The wall keeps what the door does not cover: 0-1 and 2-4.
  ASSERT_EQ(parse.plan.segments.size(), 2u);
  EXPECT_EQ(parse.plan.segments[0].b, Eigen::Vector2d(1, 0));
  EXPECT_EQ(parse.plan.segments[1].a, Eigen::Vector2d(2, 0));
  ASSERT_EQ(parse.plan.openings.size(), 1u);
  EXPECT_EQ(parse.plan.openings[0].kind, LineKind::kDoor);
  // Neither the Point at (9, 9) nor the label stretched the bounds.
  EXPECT_EQ(parse.plan.max, Eigen::Vector2d(4, 0));
}

// Every kind, with the synonyms plans use, and rooms with their names, read back from the
// GeoJSON we write; a name with a quote stays valid JSON.
TEST(GeoJsonTest, KindsAndRoomsSurviveTheRoundTrip) {
  std::string features;
  const char* kinds[] = {"wall", "window", "glazing", "stairs", "lift", "opening", "exit"};
  for (int i = 0; i < 7; ++i) {
    const std::string y = std::to_string(i);
    features +=
        Feature(R"({"type":"LineString","coordinates":[[0,)" + y + "],[3," + y + "]]}", kinds[i]) +
        ",";
  }
  features += R"({"type":"Feature","properties":{"kind":"room","name":"Lab \"B\""},"geometry":)"
              R"({"type":"Polygon","coordinates":[[[0,0],[3,0],[3,6],[0,6],[0,0]]]}})";
  const auto first = ParseGeoJsonFloorPlan(Collection(features), "t");
  ASSERT_TRUE(first.ok()) << first.error;
  const auto again = ParseGeoJsonFloorPlan(ToGeoJson(first.plan, "test \"quoted\""), "t");
  ASSERT_TRUE(again.ok()) << again.error;
  for (const FloorPlan* plan : {&first.plan, &again.plan}) {
    ASSERT_EQ(plan->segments.size(), 5u);
    EXPECT_EQ(plan->KindOf(0), LineKind::kWall);
    EXPECT_EQ(plan->KindOf(1), LineKind::kWindow);
    EXPECT_EQ(plan->KindOf(2), LineKind::kGlass);
    EXPECT_EQ(plan->KindOf(3), LineKind::kStairs);
    EXPECT_EQ(plan->KindOf(4), LineKind::kElevator);
    ASSERT_EQ(plan->openings.size(), 2u);
    EXPECT_EQ(plan->openings[0].kind, LineKind::kDoor);
    EXPECT_EQ(plan->openings[1].kind, LineKind::kExit);
    ASSERT_EQ(plan->rooms.size(), 1u);
    EXPECT_EQ(plan->rooms[0].name, "Lab \"B\"");
    EXPECT_EQ(plan->rooms[0].outline.size(), 5u);
  }
  EXPECT_EQ(FloorPlanDigest(first.plan), FloorPlanDigest(again.plan));
}

TEST(GeoJsonTest, DuplicateEdgesOfTouchingRoomsAreDropped) {
  // Two rooms sharing the wall x = 4, drawn in opposite directions.
  const auto parse = ParseGeoJsonFloorPlan(
      Collection(Feature(R"({"type":"Polygon","coordinates":[[[0,0],[4,0],[4,3],[0,3],[0,0]]]})") +
                 "," +
                 Feature(R"({"type":"Polygon","coordinates":[[[4,0],[8,0],[8,3],[4,3],[4,0]]]})")),
      "t");
  ASSERT_TRUE(parse.ok()) << parse.error;
  EXPECT_EQ(parse.plan.segments.size(), 7u);
  EXPECT_EQ(parse.dropped_segments, 1u);
}

struct BrokenCase {
  const char* name;
  std::string text;
  const char* error_part;
};

// Test failures name the case rather than dumping its bytes.
void PrintTo(const BrokenCase& c, std::ostream* os) { *os << c.name; }

class GeoJsonBrokenTest : public ::testing::TestWithParam<BrokenCase> {};

TEST_P(GeoJsonBrokenTest, GivesClearError) {
  const auto parse = ParseGeoJsonFloorPlan(GetParam().text, "broken");
  EXPECT_FALSE(parse.ok());
  EXPECT_THAT(parse.error, HasSubstr(GetParam().error_part));
  EXPECT_TRUE(parse.plan.segments.empty());
}

INSTANTIATE_TEST_SUITE_P(
    Cases, GeoJsonBrokenTest,
    ::testing::Values(
        BrokenCase{"Empty", "", "not valid JSON"},
        BrokenCase{"NotJson", "walls: 4", "not valid JSON"},
        BrokenCase{"Truncated", R"({"type":"FeatureCollection","features":[)", "not valid JSON"},
        BrokenCase{"TopLevelArray", "[[0,0],[1,0]]", "top level is not a GeoJSON object"},
        BrokenCase{"TopLevelNumber", "42", "top level"},
        BrokenCase{"NoType", R"({"features":[]})", "top level"},
        BrokenCase{"FeaturesNotArray", R"({"type":"FeatureCollection","features":{}})",
                   "without features"},
        BrokenCase{"EmptyCollection", R"({"type":"FeatureCollection","features":[]})",
                   "no usable wall segments"},
        BrokenCase{
            "OnlyDoors",
            Collection(Feature(R"({"type":"LineString","coordinates":[[0,0],[1,0]]})", "door")),
            "no usable wall segments"},
        BrokenCase{
            "CoordinatesNotNumbers",
            Collection(Feature(R"({"type":"LineString","coordinates":[["0","0"],["1","0"]]})")),
            "bad coordinates in a LineString"},
        BrokenCase{"CoordinatesNotArray",
                   Collection(Feature(R"({"type":"Polygon","coordinates":"square"})")),
                   "bad coordinates in a Polygon"},
        BrokenCase{"PositionTooShort",
                   Collection(Feature(R"({"type":"MultiLineString","coordinates":[[[0],[1,0]]]})")),
                   "bad coordinates in a MultiLineString"},
        BrokenCase{"MissingCoordinates", Collection(Feature(R"({"type":"LineString"})")),
                   "without coordinates"},
        BrokenCase{"MissingGeometryType", Collection(Feature(R"({"coordinates":[[0,0],[1,0]]})")),
                   "feature 0: geometry without a type"},
        BrokenCase{"UnsupportedType",
                   Collection(Feature(R"({"type":"Circle","coordinates":[0,0]})")),
                   "unsupported geometry type Circle"},
        BrokenCase{"FeatureNotObject", Collection("7"), "feature 0: feature is not an object"},
        BrokenCase{"DeepNesting", DeeplyNested(20), "nested too deep"}),
    [](const ::testing::TestParamInfo<BrokenCase>& c) { return c.param.name; });

class LoadFloorPlanTest : public testing::TempDirTest {};

TEST_F(LoadFloorPlanTest, ChoosesTheParserByExtension) {
  const std::string geojson =
      Collection(Feature(R"({"type":"LineString","coordinates":[[0,0],[4,0],[4,3]]})"));
  for (const char* name : {"plan.geojson", "plan.json"}) {
    const auto parse = LoadFloorPlan(Write(name, geojson));
    ASSERT_TRUE(parse.ok()) << parse.error;
    EXPECT_EQ(parse.plan.id, "plan");  // the file's stem
    EXPECT_EQ(parse.plan.segments.size(), 2u);
  }
  const auto text = LoadFloorPlan(Write("corridor.txt", "2\n0 0 10 0\n0 2 10 2\n"));
  ASSERT_TRUE(text.ok()) << text.error;
  EXPECT_EQ(text.plan.id, "corridor");
  EXPECT_EQ(text.plan.segments.size(), 2u);
}

TEST_F(LoadFloorPlanTest, ErrorsNameTheFile) {
  const std::string unknown = Write("plan.dxf", "0\nSECTION\n");
  auto parse = LoadFloorPlan(unknown);
  EXPECT_FALSE(parse.ok());
  EXPECT_THAT(parse.error, HasSubstr(unknown));
  EXPECT_THAT(parse.error, HasSubstr("'.dxf'"));

  const std::string bad_text = Write("bad.txt", "3\n0 0 1 0\n");
  parse = LoadFloorPlan(bad_text);
  EXPECT_FALSE(parse.ok());
  EXPECT_THAT(parse.error, HasSubstr(bad_text));
  EXPECT_THAT(parse.error, HasSubstr("segment 2 of 3"));

  const std::string bad_json = Write("bad.geojson", "{");
  parse = LoadFloorPlan(bad_json);
  EXPECT_THAT(parse.error, HasSubstr(bad_json));
  EXPECT_THAT(parse.error, HasSubstr("not valid JSON"));

  parse = LoadFloorPlan(Path("missing.geojson"));
  EXPECT_FALSE(parse.ok());
  EXPECT_THAT(parse.error, HasSubstr("missing.geojson"));

  parse = LoadFloorPlan(dir_.string());  // a directory
  EXPECT_FALSE(parse.ok());
  EXPECT_THAT(parse.error, HasSubstr("not a readable file"));

  parse = LoadFloorPlan(Write("empty.txt", ""));
  EXPECT_THAT(parse.error, HasSubstr("segment count missing"));
}

TEST_F(LoadFloorPlanTest, ReadFileHonoursTheSizeLimit) {
  const std::string path = Write("big.txt", std::string(1000, 'x'));
  std::string contents, error;
  EXPECT_FALSE(ReadFile(path, 999, &contents, &error));
  EXPECT_THAT(error, HasSubstr("over the limit of 999"));
  ASSERT_TRUE(ReadFile(path, 1000, &contents, &error)) << error;
  EXPECT_EQ(contents.size(), 1000u);
  // Binary content survives (no text-mode translation).
  const std::string binary("a\0b\r\nc", 6);
  ASSERT_TRUE(ReadFile(Write("bin", binary), 100, &contents, &error)) << error;
  EXPECT_EQ(contents, binary);
}

TEST_F(LoadFloorPlanTest, PlanDirectoryByIdOnly) {
  Write("office.geojson", "{}");
  Write("annex.txt", "0\n");
  Write("annex.json", "{}");  // one id, whichever file comes first
  Write("notes.md", "");
  Write(".hidden.geojson", "{}");
  std::filesystem::create_directories(dir_ / "sub.geojson");  // a directory, not a plan
  EXPECT_EQ(ListPlanIds(dir_.string()), (std::vector<std::string>{"annex", "office"}));
  EXPECT_TRUE(ListPlanIds(Path("missing")).empty());
  EXPECT_TRUE(ListPlanIds("").empty());

  std::string path, error;
  ASSERT_TRUE(FindPlanFile(dir_.string(), "office", &path, &error)) << error;
  EXPECT_EQ(path, Path("office.geojson"));
  ASSERT_TRUE(FindPlanFile(dir_.string(), "annex", &path, &error)) << error;
  EXPECT_EQ(path, Path("annex.json"));  // .geojson, .json, .txt, in that order
  for (const char* bad : {"../office", "a/b", "/etc/passwd", ".hidden", "", "sub dir"}) {
    EXPECT_FALSE(FindPlanFile(dir_.string(), bad, &path, &error)) << bad;
    EXPECT_THAT(error, HasSubstr("invalid plan id")) << bad;
  }
  EXPECT_FALSE(FindPlanFile(dir_.string(), "sub", &path, &error));
  EXPECT_THAT(error, HasSubstr("no plan 'sub'"));
  EXPECT_FALSE(FindPlanFile("", "office", &path, &error));
  EXPECT_THAT(error, HasSubstr("no plan directory configured"));
}

// The header of a thesis text file: the number of segments it lists.
size_t HeaderCount(const std::filesystem::path& txt) {
  std::istringstream in(testing::ReadText(txt));
  size_t n = 0;
  in >> n;
  return n;
}

TEST(RealFloorPlansTest, TextAndGeoJsonLoadTheSameWalls) {
  const auto data = testing::DataDir();
  if (!data) GTEST_SKIP() << testing::kNoDataMessage;
  const auto files = testing::RealPlanTextFiles(*data);
  ASSERT_FALSE(files.empty()) << "no floorplans/*/*.txt under " << *data;
  for (const auto& txt : files) {
    SCOPED_TRACE(txt.string());
    const auto text = LoadFloorPlan(txt.string());
    ASSERT_TRUE(text.ok()) << text.error;
    // Every listed segment is either kept or counted as dropped (zero-length or a
    // duplicate, e.g. coincident end caps of abutting wall rectangles).
    EXPECT_EQ(text.plan.segments.size() + text.dropped_segments, HeaderCount(txt));
    EXPECT_GT(static_cast<double>(text.plan.segments.size()),
              0.8 * static_cast<double>(HeaderCount(txt)));

    auto geojson_path = txt;
    geojson_path.replace_extension(".geojson");
    ASSERT_TRUE(std::filesystem::exists(geojson_path));
    const auto geojson = LoadFloorPlan(geojson_path.string());
    ASSERT_TRUE(geojson.ok()) << geojson.error;
    EXPECT_EQ(geojson.plan.id, text.plan.id);
    // Same walls in the same order (doors, only in the GeoJSON, are skipped); the text
    // file rounds to 0.1 mm.
    ASSERT_EQ(geojson.plan.segments.size(), text.plan.segments.size());
    EXPECT_EQ(geojson.dropped_segments, text.dropped_segments);
    for (size_t i = 0; i < text.plan.segments.size(); ++i) {
      EXPECT_NEAR((geojson.plan.segments[i].a - text.plan.segments[i].a).norm(), 0.0, 1e-4)
          << "segment " << i;
      EXPECT_NEAR((geojson.plan.segments[i].b - text.plan.segments[i].b).norm(), 0.0, 1e-4)
          << "segment " << i;
    }
    EXPECT_NEAR((geojson.plan.min - text.plan.min).norm(), 0.0, 1e-4);
    EXPECT_NEAR((geojson.plan.max - text.plan.max).norm(), 0.0, 1e-4);
  }
}

// A .floors set: one floor per line, plans relative to the set, comments; broken sets
// say which line and why.
TEST(FloorSetTest, ParsesFloorsAndRefusesBrokenSets) {
  const FloorSet set = ParseFloorSet(
      "# a building\n\n-1 -3.2 basement.geojson\n0 0 ground.txt   # lobby\n"
      "1 3.5 /plans/first.yaml\n",
      "/site", "b.floors");
  ASSERT_TRUE(set.ok()) << set.error;
  ASSERT_EQ(set.floors.size(), 3u);
  EXPECT_EQ(set.floors[0].id, "-1");
  EXPECT_DOUBLE_EQ(set.floors[0].height_m, -3.2);
  EXPECT_EQ(set.floors[0].plan_path, "/site/basement.geojson");
  EXPECT_EQ(set.floors[2].plan_path, "/plans/first.yaml");
  ASSERT_NE(set.Find("1"), nullptr);
  EXPECT_EQ(set.Find("2"), nullptr);
  EXPECT_EQ(set.Nearest(1.4).id, "0");
  EXPECT_EQ(set.Nearest(2.0).id, "1");
  EXPECT_EQ(set.Nearest(-100).id, "-1");

  for (const auto& [text, why] : std::vector<std::pair<std::string, std::string>>{
           {"", "no floors"},
           {"0 0\n", "b.floors:1: expected"},
           {"0 0 a.txt extra\n", "expected"},
           {"0 zero a.txt\n", "expected"},
           {"0 nan a.txt\n", "not a number"},
           {"0 0 a.txt\n0 3 b.txt\n", "b.floors:2: floor '0' twice"},
           {"0 0 a.txt\n1 0.4 b.txt\n", "within 1 m"}}) {
    const FloorSet bad = ParseFloorSet(text, "", "b.floors");
    EXPECT_THAT(bad.error, HasSubstr(why)) << text;
  }
  EXPECT_TRUE(IsFloorSet("/x/building.floors"));
  EXPECT_FALSE(IsFloorSet("/x/plan.geojson"));
  EXPECT_THAT(LoadFloorSet("/no/such.floors").error, HasSubstr("/no/such.floors"));
}

}  // namespace
}  // namespace floorpose::platform
