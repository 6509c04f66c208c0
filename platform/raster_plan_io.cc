#include "platform/raster_plan_io.h"

#include <png.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <vector>

#include "platform/floor_plan_io.h"

namespace floorpose::platform {
namespace {

constexpr size_t kMaxYamlBytes = 64 << 10;
constexpr size_t kMaxImageBytes = 256u << 20;
constexpr png_uint_32 kMaxSide = 1 << 15;  // 1.6 km at 5 cm

struct MapYaml {
  std::string image;
  double resolution = 0, occupied_thresh = 0.65, free_thresh = 0.196;
  double origin[3] = {0, 0, 0};
  bool negate = false;
};

std::string ParseMapYaml(const std::string& text, MapYaml* m) {
  try {
    const YAML::Node doc = YAML::Load(text);
    if (!doc.IsMap()) return "not a YAML mapping";
    for (const char* key : {"image", "resolution", "origin"})
      if (!doc[key]) return std::string("missing '") + key + "'";
    m->image = doc["image"].as<std::string>();
    m->resolution = doc["resolution"].as<double>();
    const YAML::Node origin = doc["origin"];
    if (!origin.IsSequence() || origin.size() < 2 || origin.size() > 3)
      return "origin must be [x, y] or [x, y, yaw]";
    for (size_t i = 0; i < origin.size(); ++i) m->origin[i] = origin[i].as<double>();
    if (doc["negate"]) m->negate = doc["negate"].as<int>() != 0;
    if (doc["occupied_thresh"]) m->occupied_thresh = doc["occupied_thresh"].as<double>();
    if (doc["free_thresh"]) m->free_thresh = doc["free_thresh"].as<double>();
  } catch (const YAML::Exception& e) {
    return std::string("YAML: ") + e.what();
  }
  if (m->image.empty()) return "empty 'image'";
  if (!(m->resolution > 0) || !std::isfinite(m->resolution))
    return "resolution must be a positive number of metres per pixel";
  if (!std::isfinite(m->origin[0]) || !std::isfinite(m->origin[1])) return "origin must be finite";
  if (m->origin[2] != 0)
    return "a rotated origin (yaw " + std::to_string(m->origin[2]) +
           ") is not supported: rotate the image instead";
  if (!(m->occupied_thresh > 0 && m->occupied_thresh < 1) ||
      !(m->free_thresh >= 0 && m->free_thresh < m->occupied_thresh))
    return "need 0 <= free_thresh < occupied_thresh < 1";
  return {};
}

// Reads any PNG as 8-bit grey (libpng's simplified API converts colour, palette and
// 16-bit images; transparent pixels are composed onto white, i.e. free).
std::string ReadGreyPng(const std::string& path, int* width, int* height,
                        std::vector<uint8_t>* grey) {
  std::string bytes, error;
  if (!ReadFile(path, kMaxImageBytes, &bytes, &error)) return error;
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, bytes.data(), bytes.size()))
    return path + ": not a PNG image (" + image.message + ")";
  auto release = std::unique_ptr<png_image, void (*)(png_image*)>(&image, png_image_free);
  if (image.width == 0 || image.height == 0 || image.width > kMaxSide || image.height > kMaxSide)
    return path + ": image size " + std::to_string(image.width) + " x " +
           std::to_string(image.height) + " out of range (1.." + std::to_string(kMaxSide) + ")";
  // Before allocating: a few bytes of header may claim a gigabyte of pixels.
  const size_t max_cells = RasterPlanOptions{}.max_cells;
  if (size_t{image.width} * image.height > max_cells)
    return path + ": image of " + std::to_string(image.width) + " x " +
           std::to_string(image.height) + " pixels, more than " + std::to_string(max_cells);
  image.format = PNG_FORMAT_GRAY;
  grey->resize(PNG_IMAGE_SIZE(image));
  png_color background{255, 255, 255};  // transparent pixels are free, not walls
  if (!png_image_finish_read(&image, &background, grey->data(), 0, nullptr))
    return path + ": corrupt PNG (" + image.message + ")";
  *width = static_cast<int>(image.width);
  *height = static_cast<int>(image.height);
  return {};
}

}  // namespace

bool LoadOccupancyRaster(const std::string& yaml_path, OccupancyRaster* raster,
                         std::string* error) {
  std::string text;
  if (!ReadFile(yaml_path, kMaxYamlBytes, &text, error)) return false;
  MapYaml m;
  if (std::string e = ParseMapYaml(text, &m); !e.empty()) {
    *error = yaml_path + ": " + e;
    return false;
  }
  const std::filesystem::path image_path =
      std::filesystem::path(yaml_path).parent_path() / std::filesystem::path(m.image);
  std::vector<uint8_t> grey;
  int w = 0, h = 0;
  if (std::string e = ReadGreyPng(image_path.string(), &w, &h, &grey); !e.empty()) {
    *error = yaml_path + ": " + e;
    return false;
  }
  raster->width = w;
  raster->height = h;
  raster->resolution_m = m.resolution;
  raster->origin = {m.origin[0], m.origin[1]};
  raster->occupied.resize(grey.size());
  for (size_t i = 0; i < grey.size(); ++i) {
    const double occupancy = m.negate ? grey[i] / 255.0 : (255 - grey[i]) / 255.0;
    raster->occupied[i] = occupancy > m.occupied_thresh ? 1 : 0;
  }
  return true;
}

FloorPlanParse LoadRasterFloorPlan(const std::string& yaml_path, RasterPlanReport* report) {
  FloorPlanParse out;
  OccupancyRaster raster;
  if (!LoadOccupancyRaster(yaml_path, &raster, &out.error)) return out;
  out = FloorPlanFromRaster(raster, std::filesystem::path(yaml_path).stem().string(), {}, report);
  if (!out.ok()) out.error = yaml_path + ": " + out.error;
  return out;
}

}  // namespace floorpose::platform
