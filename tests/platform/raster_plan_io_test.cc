// Raster floor plans from files: a PNG written here with libpng, with its map_server YAML.
#include "platform/raster_plan_io.h"

#include <png.h>

#include "platform/floor_plan_io.h"
#include "tests/test_util.h"

namespace floorpose::platform {
namespace {

class RasterPlanIoTest : public testing::TempDirTest {
 protected:
  // A 60 x 40 pixel plan: a black frame one pixel wide (walls), white inside, and a grey
  // blot (occupancy 0.5: not a wall under the default thresholds).
  std::string WritePng(const std::string& name) {
    std::vector<uint8_t> grey(60 * 40, 255);
    for (int c = 0; c < 60; ++c) grey[c] = grey[39 * 60 + c] = 0;
    for (int r = 0; r < 40; ++r) grey[r * 60] = grey[r * 60 + 59] = 0;
    for (int r = 15; r < 20; ++r)
      for (int c = 25; c < 30; ++c) grey[r * 60 + c] = 128;
    png_image image{};
    image.version = PNG_IMAGE_VERSION;
    image.width = 60;
    image.height = 40;
    image.format = PNG_FORMAT_GRAY;
    EXPECT_TRUE(png_image_write_to_file(&image, Path(name).c_str(), 0, grey.data(), 0, nullptr))
        << image.message;
    return Path(name);
  }
  std::string WriteYaml(const std::string& name, const std::string& image,
                        const std::string& extra = "") {
    return Write(name, "image: " + image +
                           "\nresolution: 0.05\norigin: [-1.0, 2.0, 0.0]\nnegate: 0\n"
                           "occupied_thresh: 0.65\nfree_thresh: 0.196\n" +
                           extra);
  }
};

TEST_F(RasterPlanIoTest, LoadsTheWallsInTheYamlsFrame) {
  WritePng("plan.png");
  const std::string yaml = WriteYaml("plan.yaml", "plan.png");
  const FloorPlanParse parsed = LoadFloorPlan(yaml);  // chosen by the extension
  ASSERT_TRUE(parsed.ok()) << parsed.error;
  EXPECT_EQ(parsed.plan.id, "plan");
  // The frame's four sides (and their corners' cells), not the blot.
  EXPECT_GE(parsed.plan.segments.size(), 4u);
  EXPECT_LE(parsed.plan.segments.size(), 8u);
  // Pixel centres of the frame: x from -1 + 0.025 to -1 + 2.975, y from 2.025 to 3.975.
  EXPECT_NEAR(parsed.plan.min.x(), -1.0, 0.03);
  EXPECT_NEAR(parsed.plan.max.x(), 2.0, 0.03);
  EXPECT_NEAR(parsed.plan.min.y(), 2.0, 0.03);
  EXPECT_NEAR(parsed.plan.max.y(), 4.0, 0.03);
  // Plans of a plan directory include rasters.
  EXPECT_THAT(ListPlanIds(dir_.string()), ::testing::ElementsAre("plan"));
}

TEST_F(RasterPlanIoTest, NegateMakesWhiteTheWalls) {
  WritePng("plan.png");
  const std::string yaml =
      Write("neg.yaml", "image: plan.png\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 1\n");
  RasterPlanReport report;
  const FloorPlanParse parsed = LoadRasterFloorPlan(yaml, &report);
  ASSERT_TRUE(parsed.ok()) << parsed.error;
  EXPECT_GT(report.occupied, 1000u);  // the white inside is now occupied
}

TEST_F(RasterPlanIoTest, BrokenFilesFailClearly) {
  WritePng("plan.png");
  Write("junk.png", "not a png at all");
  const std::string truncated = Write("cut.png", testing::ReadText(Path("plan.png")).substr(0, 60));
  struct Case {
    std::string yaml, expected;
  };
  const std::vector<Case> cases = {
      {"image: plan.png\norigin: [0, 0, 0]\n", "missing 'resolution'"},
      {"image: plan.png\nresolution: 0\norigin: [0, 0, 0]\n", "resolution must be"},
      {"image: plan.png\nresolution: 0.05\norigin: [0, 0, 0.3]\n", "rotated origin"},
      {"image: plan.png\nresolution: 0.05\norigin: 5\n", "origin must be"},
      {"image: missing.png\nresolution: 0.05\norigin: [0, 0, 0]\n", "not a readable file"},
      {"image: junk.png\nresolution: 0.05\norigin: [0, 0, 0]\n", "not a PNG"},
      {"image: cut.png\nresolution: 0.05\norigin: [0, 0, 0]\n", "corrupt PNG"},
      {"image: plan.png\nresolution: [\n", "YAML"},
      {"image: plan.png\nresolution: 0.05\norigin: [0, 0, 0]\noccupied_thresh: 2\n",
       "occupied_thresh"},
  };
  for (const Case& c : cases) {
    const std::string yaml = Write("bad.yaml", c.yaml);
    const FloorPlanParse parsed = LoadFloorPlan(yaml);
    EXPECT_FALSE(parsed.ok()) << c.yaml;
    EXPECT_THAT(parsed.error, ::testing::HasSubstr(c.expected)) << c.yaml;
    EXPECT_THAT(parsed.error, ::testing::HasSubstr("bad.yaml")) << c.yaml;
  }
}

// A few bytes of PNG header may claim a gigabyte of pixels: refused before allocating.
TEST_F(RasterPlanIoTest, AHeaderClaimingHugeDimensionsIsRefusedBeforeReading) {
  std::string png = testing::ReadText(WritePng("plan.png"));
  ASSERT_EQ(png.substr(12, 4), "IHDR");
  for (int i = 0; i < 2; ++i) {  // width, height: 32000 (big-endian)
    png[16 + 4 * i + 2] = static_cast<char>(32000 >> 8);
    png[16 + 4 * i + 3] = static_cast<char>(32000 & 0xff);
  }
  uint32_t crc = 0xffffffffu;  // PNG's CRC-32 over the chunk type and data
  for (int k = 12; k < 29; ++k) {
    crc ^= static_cast<uint8_t>(png[k]);
    for (int b = 0; b < 8; ++b) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  crc = ~crc;
  for (int i = 0; i < 4; ++i) png[29 + i] = static_cast<char>(crc >> (24 - 8 * i));
  Write("huge.png", png);
  const FloorPlanParse parsed = LoadFloorPlan(WriteYaml("huge.yaml", "huge.png"));
  EXPECT_FALSE(parsed.ok());
  EXPECT_THAT(parsed.error, ::testing::HasSubstr("image of 32000 x 32000 pixels, more than"));
}

TEST(RasterPlanDataTest, CarmenPlansLoad) {
  const auto data = testing::DataDir();
  if (!data) GTEST_SKIP() << testing::kNoDataMessage;
  for (const char* name : {"aces", "csail", "freiburg-101", "orebro"}) {
    RasterPlanReport report;
    const FloorPlanParse parsed = LoadRasterFloorPlan(
        (*data / "carmen" / (std::string(name) + "_plan.yaml")).string(), &report);
    ASSERT_TRUE(parsed.ok()) << parsed.error;
    // The data set's README: 16305, 20074, 10539 and 8765 occupied pixels.
    EXPECT_GT(report.occupied, 8000u) << name;
    EXPECT_LT(report.isolated, report.occupied / 8) << name;  // orebro: 10% specks
    // Connected cells along one line are one wall: a few cells a segment at least.
    EXPECT_LT(parsed.plan.segments.size(), (report.occupied - report.isolated) / 2) << name;
  }
}

}  // namespace
}  // namespace floorpose::platform
