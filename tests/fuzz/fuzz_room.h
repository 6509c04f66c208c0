// What the fuzz targets that drive a real Engine share: the device they speak for, a
// small room plan written once to a per-process directory (removed at exit), and quiet
// logs (every rejection is logged: noise, and slow; FLOORPOSE_FUZZ_LOG=1 shows the log
// when replaying one input).
#pragma once

#include <google/protobuf/stubs/logging.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace floorpose::fuzz {

inline constexpr char kDevice[] = "fuzz-headset";

// A 6 x 4 m room with a wall stub, so that it has one right way round (small: the engine
// indexes it for every input). Plan x/y = Unity x/z.
inline constexpr char kRoomPlan[] = R"({"type": "FeatureCollection", "features": [
  {"type": "Feature", "geometry": {"type": "Polygon",
   "coordinates": [[[0, 0], [6, 0], [6, 4], [0, 4], [0, 0]]]}},
  {"type": "Feature", "geometry": {"type": "LineString", "coordinates": [[2, 0], [2, 1.5]]}}]})";

inline std::filesystem::path& WorkDir() {
  static std::filesystem::path dir;
  return dir;
}

// Once, from LLVMFuzzerInitialize: the logs quietened, and <tmp>/floorpose-<name>-<pid>/
// with room.geojson in it; returns that directory.
inline std::filesystem::path SetUp(const std::string& name) {
  if (!std::getenv("FLOORPOSE_FUZZ_LOG")) {
    spdlog::set_level(spdlog::level::off);
    google::protobuf::SetLogHandler(nullptr);
  }
  WorkDir() = std::filesystem::temp_directory_path() /
              ("floorpose-" + name + "-" + std::to_string(getpid()));
  std::filesystem::create_directories(WorkDir());
  std::atexit([] {
    std::error_code ec;
    std::filesystem::remove_all(WorkDir(), ec);
  });
  std::ofstream(WorkDir() / "room.geojson") << kRoomPlan;
  return WorkDir();
}

}  // namespace floorpose::fuzz
