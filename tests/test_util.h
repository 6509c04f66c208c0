// Helpers shared by the test suites: seeded random geometry, a tolerance matcher for
// SE(2) transforms (after Cartographer's rigid_transform_test_helpers.h) and access to
// the developer data set.
#pragma once

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/floor_plan.h"
#include "core/random.h"
#include "core/se2.h"

namespace floorpose::testing {

inline double Deg(double degrees) { return degrees * M_PI / 180.0; }

// A rotation drawn uniformly: a normalised 4D Gaussian vector.
inline Eigen::Quaterniond RandomRotation(SplitMix64& rng) {
  Eigen::Quaterniond q(rng.Gaussian(), rng.Gaussian(), rng.Gaussian(), rng.Gaussian());
  return q.normalized();
}

inline Eigen::Vector3d RandomVector3(SplitMix64& rng, double lo, double hi) {
  return {rng.Uniform(lo, hi), rng.Uniform(lo, hi), rng.Uniform(lo, hi)};
}

inline Eigen::Vector2d RandomVector2(SplitMix64& rng, const Eigen::Vector2d& lo,
                                     const Eigen::Vector2d& hi) {
  return {rng.Uniform(lo.x(), hi.x()), rng.Uniform(lo.y(), hi.y())};
}

inline Se2 RandomSe2(SplitMix64& rng, double max_angle_rad, double max_translation_m) {
  return {rng.Uniform(-max_angle_rad, max_angle_rad),
          {rng.Uniform(-max_translation_m, max_translation_m),
           rng.Uniform(-max_translation_m, max_translation_m)}};
}

// Matches an Se2 within a translation (metres) and rotation (radians) tolerance.
MATCHER_P3(IsNearlySe2, expected, max_translation_m, max_rotation_rad,
           "is within " + ::testing::PrintToString(max_translation_m) + " m and " +
               ::testing::PrintToString(max_rotation_rad) + " rad of the expected transform") {
  const Se2& e = expected;
  const double dtheta = std::abs(WrapAngle(arg.theta - e.theta));
  const double dt = (arg.t - e.t).norm();
  *result_listener << "theta " << arg.theta << " (expected " << e.theta << ", off " << dtheta
                   << " rad), t (" << arg.t.x() << ", " << arg.t.y() << ") (expected (" << e.t.x()
                   << ", " << e.t.y() << "), off " << dt << " m)";
  return dtheta <= max_rotation_rad && dt <= max_translation_m;
}

// A 10 x 7 m room with an inner wall and a short stub: no symmetry that registration
// could confuse with the truth.
inline FloorPlan AsymmetricRoom() {
  auto parse = MakeFloorPlan("room", {{{0, 0}, {10, 0}},
                                      {{10, 0}, {10, 7}},
                                      {{10, 7}, {0, 7}},
                                      {{0, 7}, {0, 0}},
                                      {{4, 0}, {4, 4.5}},  // inner wall
                                      {{7, 7}, {7, 5.5}},  // stub from the top wall
                                      {{4, 4.5}, {5.5, 4.5}}});
  EXPECT_TRUE(parse.ok()) << parse.error;
  return parse.plan;
}

// Points evenly spaced along every segment of a plan (both ends included).
inline std::vector<Eigen::Vector2d> SampleWalls(const FloorPlan& plan, double spacing_m) {
  std::vector<Eigen::Vector2d> out;
  for (const Segment& s : plan.segments) {
    const int n = std::max(1, static_cast<int>(std::ceil(s.Length() / spacing_m)));
    for (int i = 0; i <= n; ++i) out.push_back(s.a + (s.b - s.a) * (static_cast<double>(i) / n));
  }
  return out;
}

// A plan in the thesis' text format (core/floor_plan.h ParseTextFloorPlan), to write as
// a .txt plan file.
inline std::string ThesisText(const FloorPlan& plan) {
  std::string text = std::to_string(plan.segments.size()) + "\n";
  for (const Segment& s : plan.segments)
    text += std::to_string(s.a.x()) + " " + std::to_string(s.a.y()) + " " +
            std::to_string(s.b.x()) + " " + std::to_string(s.b.y()) + "\n";
  return text;
}

// The developer data set, from FLOORPOSE_DATA; nothing when unset or empty.
inline std::optional<std::filesystem::path> DataDir() {
  const char* dir = std::getenv("FLOORPOSE_DATA");
  if (!dir || !*dir) return std::nullopt;
  return std::filesystem::path(dir);
}

inline constexpr char kNoDataMessage[] =
    "FLOORPOSE_DATA not set: point it at the developer data set (the directory holding "
    "floorplans/) to run the real-floor-plan tests";

// Every $FLOORPOSE_DATA/floorplans/*/*.txt, sorted.
inline std::vector<std::filesystem::path> RealPlanTextFiles(const std::filesystem::path& data) {
  std::vector<std::filesystem::path> out;
  std::error_code ec;
  for (const auto& dir : std::filesystem::directory_iterator(data / "floorplans", ec)) {
    if (!dir.is_directory()) continue;
    for (const auto& f : std::filesystem::directory_iterator(dir.path(), ec))
      if (f.path().extension() == ".txt" && f.path().filename().string().rfind("LICENSE", 0) != 0)
        out.push_back(f.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

inline std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The running test's own directory under ::testing::TempDir(), by suite, name and process.
// A parameterised test's name has a '/' ("Name/0"): made '_', so that it is one directory,
// not one inside another that removing it would leave behind.
inline std::filesystem::path TestDirectory() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string("floorpose_") + info->test_suite_name() + "_" + info->name() +
                     "_" + std::to_string(getpid());
  std::replace(name.begin(), name.end(), '/', '_');
  return std::filesystem::path(::testing::TempDir()) / name;
}

// A fresh directory per test (and process) under ::testing::TempDir(), removed afterwards,
// or kept with a line saying where when the test failed (daemon logs, recordings).
class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = TestDirectory();
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    if (HasFailure()) {
      std::cerr << "test files kept in " << dir_.string() << "\n";
      return;
    }
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  // Writes a file in the test's directory; returns its path.
  std::string Write(const std::string& name, const std::string& contents) const {
    const auto path = dir_ / name;
    std::ofstream(path, std::ios::binary) << contents;
    return path.string();
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  std::filesystem::path dir_;
};

}  // namespace floorpose::testing
