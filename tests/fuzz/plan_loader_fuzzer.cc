// Floor plan files through platform::LoadFloorPlan, as the daemon loads them (plan_path,
// Command.load_plan): GeoJSON, the thesis' text format and raster plans (YAML + PNG).
// A plan of building size that loads also goes into the closest-wall index the daemon
// builds from it, checked against the brute-force answer.
//
// Input: byte 0 chooses the format (0 GeoJSON, 1 text, 2 raster). For GeoJSON and text
// the rest is the file. For a raster, bytes 1-2 (little endian) are the YAML's length,
// then the YAML, then the PNG; the YAML names its image (the seeds say plan.png).
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "core/closest_wall_index.h"
#include "platform/floor_plan_io.h"

namespace floorpose::platform {
namespace {

std::filesystem::path dir;

void RemoveDir() {
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
}

void Check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "plan_loader_fuzzer: broken promise: %s\n", what);
  std::abort();
}

std::string Write(const std::string& name, std::string_view bytes) {
  const std::filesystem::path p = dir / name;
  std::ofstream(p, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return p.string();
}

// The daemon's index (Engine::LoadPlan's options) answers as trying every wall would.
void CheckIndex(const FloorPlan& plan) {
  ClosestWallIndex::Options options;
  options.max_distance_m = 3.0;
  const ClosestWallIndex index(plan, options);
  std::vector<Eigen::Vector2d> queries = {0.5 * (plan.min + plan.max)};
  for (size_t i = 0; i < plan.segments.size() && i < 8; ++i) {
    const Segment& s = plan.segments[i];
    queries.push_back(0.5 * (s.a + s.b) + 0.5 * s.Normal());
  }
  for (const Eigen::Vector2d& q : queries) {
    const auto fast = index.Query(q);
    const auto slow = BruteForceClosestWall(plan, q, options.max_distance_m);
    // Right at the range limit rounding may decide either way.
    if (slow && slow->distance < options.max_distance_m - 1e-6) Check(fast.has_value(), "missed");
    if (fast && slow) Check(std::abs(fast->distance - slow->distance) < 1e-6, "wrong distance");
    if (fast) Check(fast->distance <= options.max_distance_m + 1e-6, "beyond range");
  }
}

}  // namespace
}  // namespace floorpose::platform

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  using floorpose::platform::dir;
  dir = std::filesystem::temp_directory_path() /
        ("floorpose-plan-loader-fuzzer-" + std::to_string(getpid()));
  std::atexit(floorpose::platform::RemoveDir);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace floorpose;
  using namespace floorpose::platform;
  if (size == 0) return 0;
  // No file of an earlier input may be found by this one (a YAML naming plan.txt).
  RemoveDir();
  std::filesystem::create_directories(dir);
  const std::string_view rest(reinterpret_cast<const char*>(data + 1), size - 1);
  std::string path;
  switch (data[0] % 3) {
    case 0: path = Write("plan.geojson", rest); break;
    case 1: path = Write("plan.txt", rest); break;
    case 2: {
      const size_t yaml_size =
          rest.size() < 2 ? 0 : static_cast<uint8_t>(rest[0]) | static_cast<uint8_t>(rest[1]) << 8;
      const std::string_view files = rest.substr(std::min<size_t>(2, rest.size()));
      path = Write("plan.yaml", files.substr(0, yaml_size));
      Write("plan.png", files.substr(std::min(yaml_size, files.size())));
      break;
    }
  }
  const FloorPlanParse parsed = LoadFloorPlan(path);
  if (!parsed.ok()) return 0;
  const FloorPlan& plan = parsed.plan;
  Check(!plan.segments.empty(), "a plan without walls");
  Check(plan.id == "plan", "plan id is not the file's stem");
  for (const Segment& s : plan.segments) {
    Check(s.a.allFinite() && s.b.allFinite() && s.Length() >= 1e-3, "unusable segment kept");
    Check((s.a.array() >= plan.min.array()).all() && (s.a.array() <= plan.max.array()).all() &&
              (s.b.array() >= plan.min.array()).all() && (s.b.array() <= plan.max.array()).all(),
          "segment outside the plan's bounds");
  }
  // Larger plans index fine too, only slowly: keep the fuzzer fast.
  if ((plan.max - plan.min).maxCoeff() <= 200) CheckIndex(plan);
  return 0;
}
