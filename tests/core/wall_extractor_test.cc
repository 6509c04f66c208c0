// Thesis Algorithm 4.1: wall points are sampled on vertical mesh faces only, as many as
// the face's area times the density, uniformly, deterministically per (seed, mesh id).
#include "core/wall_extractor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/floor_plan.h"

namespace floorpose {
namespace {

// Builds a slam-frame mesh from subdivided parallelograms.
struct MeshBuilder {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<uint32_t> triangles;

  // The parallelogram origin + [0,1] u + [0,1] v, split into nu x nv cells of two
  // triangles each. Returns the number of triangles added.
  size_t Quad(const Eigen::Vector3d& origin, const Eigen::Vector3d& u, const Eigen::Vector3d& v,
              int nu = 1, int nv = 1) {
    const auto base = static_cast<uint32_t>(vertices.size());
    for (int j = 0; j <= nv; ++j)
      for (int i = 0; i <= nu; ++i)
        vertices.push_back(
            (origin + u * (static_cast<double>(i) / nu) + v * (static_cast<double>(j) / nv))
                .cast<float>());
    auto at = [&](int i, int j) { return base + static_cast<uint32_t>(j * (nu + 1) + i); };
    for (int j = 0; j < nv; ++j) {
      for (int i = 0; i < nu; ++i) {
        triangles.insert(triangles.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        triangles.insert(triangles.end(), {at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
    return static_cast<size_t>(2 * nu * nv);
  }
  SlamMesh mesh() const { return {&vertices, &triangles}; }
};

// The 2D footprint of a vertical face: the segment its base traces on the floor.
Segment Footprint(const Eigen::Vector3d& origin, const Eigen::Vector3d& u) {
  return {origin.head<2>(), (origin + u).head<2>()};
}

double DistanceToSegment(const Segment& s, const Eigen::Vector2d& p) {
  return (ClosestPointOnSegment(s, p) - p).norm();
}

// A room whose floor, ceiling and slopes lie strictly inside the walls' outline, so a
// point sampled from any of them is far from every wall footprint.
struct Room {
  MeshBuilder mesh;
  std::vector<Segment> walls;
  double wall_area = 0;
  size_t wall_triangles = 0;

  Room() {
    const Eigen::Vector3d up(0, 0, 2.5);
    auto wall = [&](const Eigen::Vector3d& origin, const Eigen::Vector3d& u) {
      wall_triangles += mesh.Quad(origin, u, up, 6, 3);
      walls.push_back(Footprint(origin, u));
      wall_area += u.norm() * up.norm();
    };
    wall({0, 0, 0}, {0, 3, 0});        // x = 0
    wall({0, 3, 0}, {4, 0, 0});        // y = 3
    wall({4, 0, 0}, {1.5, 2, 0});      // oblique, 53 degrees
    wall({5.5, 2, 0}, {-1.5, -2, 0});  // the same face wound the other way
    // Horizontal floor and ceiling, away from the walls in 2D.
    mesh.Quad({0.5, 0.5, 0}, {3, 0, 0}, {0, 2, 0}, 4, 4);
    mesh.Quad({0.5, 0.5, 2.5}, {0, 2, 0}, {3, 0, 0}, 4, 4);
    // A ramp 30 degrees above horizontal (|n . up| = cos 30) and a face leaning 30
    // degrees off vertical (|n . up| = sin 30): neither is a wall.
    const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
    mesh.Quad({1, 1, 0}, {2, 0, 0}, {0, c, s}, 3, 3);
    mesh.Quad({1, 2, 0}, {2, 0, 0}, {0, s * 0.8, c * 0.8}, 3, 3);
  }
};

TEST(WallExtractorTest, PointsOnlyOnVerticalFaces) {
  const Room room;
  WallExtractionOptions options;
  options.density_per_m2 = 200;
  WallExtractionReport report;
  const auto points = ExtractWallPoints(room.mesh.mesh(), 1, options, &report);

  EXPECT_EQ(report.triangles, room.mesh.triangles.size() / 3);
  EXPECT_EQ(report.vertical_triangles, room.wall_triangles);
  EXPECT_EQ(report.degenerate_triangles, 0u);
  EXPECT_EQ(report.bad_indices, 0u);
  EXPECT_NEAR(report.wall_area_m2, room.wall_area, 1e-4);
  ASSERT_GT(points.size(), 0u);

  for (const WallPoint& wp : points) {
    const Eigen::Vector2d p = wp.p.cast<double>();
    double best = std::numeric_limits<double>::infinity();
    const Segment* on = nullptr;
    for (const Segment& w : room.walls) {
      const double d = DistanceToSegment(w, p);
      if (d < best) {
        best = d;
        on = &w;
      }
    }
    ASSERT_LT(best, 1e-5) << "point (" << p.transpose() << ") is on no wall";
    // The normal is unit and perpendicular to the wall it was sampled on.
    const Eigen::Vector2d n = wp.n.cast<double>();
    const Eigen::Vector2d dir = (on->b - on->a).normalized();
    EXPECT_NEAR(n.norm(), 1.0, 1e-6);
    EXPECT_NEAR(n.dot(dir), 0.0, 1e-6);
  }
}

TEST(WallExtractorTest, CountProportionalToArea) {
  // Walls of 2.6 and 10.4 square metres, far apart, in 0.1 m cells: every triangle
  // expects 2.5 points, so the random rounding matters but averages out.
  MeshBuilder b;
  const Eigen::Vector3d up(0, 0, 2);
  b.Quad({0, 0, 0}, {1.3, 0, 0}, up, 13, 20);
  b.Quad({0, 10, 0}, {5.2, 0, 0}, up, 52, 20);
  WallExtractionOptions options;
  options.density_per_m2 = 500;
  const auto points = ExtractWallPoints(b.mesh(), 3, options);
  size_t small = 0, large = 0;
  for (const WallPoint& wp : points) (wp.p.y() < 5 ? small : large)++;
  ASSERT_GT(small, 0u);
  EXPECT_NEAR(static_cast<double>(large) / static_cast<double>(small), 4.0, 4.0 * 0.03);
  EXPECT_NEAR(static_cast<double>(points.size()), 13.0 * 500, 13.0 * 500 * 0.02);
}

TEST(WallExtractorTest, SmallTrianglesAreNotLost) {
  // 80000 triangles of 1/800 square metre at 50 points per square metre: each expects
  // 0.0625 points. Rounding down would give none; the random extra point gives the
  // area times the density (binomial, 4 standard deviations allowed).
  MeshBuilder b;
  b.Quad({0, 0, 0}, {40, 0, 0}, {0, 0, 2.5}, 800, 50);
  const WallExtractionOptions options;  // 50 per square metre
  WallExtractionReport report;
  const auto points = ExtractWallPoints(b.mesh(), 5, options, &report);
  const double expected = 100.0 * options.density_per_m2;
  const double sigma = std::sqrt(80000 * 0.0625 * (1 - 0.0625));
  EXPECT_NEAR(report.wall_area_m2, 100.0, 1e-3);
  EXPECT_NEAR(static_cast<double>(points.size()), expected, 4 * sigma);
}

TEST(WallExtractorTest, UniformOverTheTriangle) {
  // The vertical triangle (0,0,0) (1,0,0) (0,0,1): uniform points have x with density
  // 2 (1 - x), mean 1/3 and E[x^2] = 1/6. The thesis' two-step interpolation would
  // crowd points at one vertex and miss these moments.
  const std::vector<Eigen::Vector3f> V = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
  const std::vector<uint32_t> F = {0, 1, 2};
  WallExtractionOptions options;
  options.density_per_m2 = 20000;
  const auto points = ExtractWallPoints({&V, &F}, 9, options);
  ASSERT_NEAR(static_cast<double>(points.size()), 10000, 1);
  double sum = 0, sum2 = 0;
  for (const WallPoint& wp : points) {
    ASSERT_GE(wp.p.x(), -1e-6f);
    ASSERT_LE(wp.p.x(), 1 + 1e-6f);
    ASSERT_EQ(wp.p.y(), 0.0f);
    sum += wp.p.x();
    sum2 += wp.p.x() * wp.p.x();
  }
  const double n = static_cast<double>(points.size());
  // Standard errors: sqrt(1/18 / n) = 0.0024 and sqrt(1/15 - 1/36) / sqrt(n) = 0.002.
  EXPECT_NEAR(sum / n, 1.0 / 3.0, 0.01);
  EXPECT_NEAR(sum2 / n, 1.0 / 6.0, 0.01);
}

bool SamePoints(const std::vector<WallPoint>& a, const std::vector<WallPoint>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i].p != b[i].p || a[i].n != b[i].n) return false;
  return true;
}

TEST(WallExtractorTest, DeterministicPerSeedAndMeshId) {
  const Room room;
  WallExtractionOptions options;
  options.seed = 7;
  const auto first = ExtractWallPoints(room.mesh.mesh(), 42, options);
  ASSERT_FALSE(first.empty());
  EXPECT_TRUE(SamePoints(first, ExtractWallPoints(room.mesh.mesh(), 42, options)));
  EXPECT_FALSE(SamePoints(first, ExtractWallPoints(room.mesh.mesh(), 43, options)));
  options.seed = 8;
  EXPECT_FALSE(SamePoints(first, ExtractWallPoints(room.mesh.mesh(), 42, options)));
}

TEST(WallExtractorTest, BadTrianglesAreCountedNotFatal) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<Eigen::Vector3f> V = {
      {0, 0, 0},     {1, 0, 0},   {0, 0, 1},  // 0-2: a good vertical triangle
      {nan, 0, 0},   {inf, 1, 0},             // 3-4: non-finite
      {2, 0, 0},     {3, 0, 0},               // 5-6: collinear with 1
      {20, 0, 0},    {20, 0, 1},              // 7-8: 20 m edges, over max_edge_m
      {1e30f, 0, 0},                          // 9: absurd coordinate
  };
  const std::vector<uint32_t> F = {
      0, 1, 2,    // good
      0, 1, 3,    // NaN vertex
      0, 4, 2,    // infinite vertex
      1, 5, 6,    // zero area, collinear
      0, 0, 2,    // zero area, repeated index
      0, 7, 8,    // too long
      0, 9, 2,    // absurdly long
      0, 1, 100,  // index out of range
      0, 1,       // a dangling partial triangle: ignored
  };
  WallExtractionOptions options;
  options.density_per_m2 = 100;
  WallExtractionReport report;
  const auto points = ExtractWallPoints({&V, &F}, 1, options, &report);
  EXPECT_EQ(report.triangles, 8u);
  EXPECT_EQ(report.bad_indices, 1u);
  EXPECT_EQ(report.degenerate_triangles, 6u);
  EXPECT_EQ(report.vertical_triangles, 1u);
  EXPECT_NEAR(report.wall_area_m2, 0.5, 1e-9);
  EXPECT_EQ(points.size(), 50u);  // 0.5 m^2 at 100 per m^2, from the good triangle only
  for (const WallPoint& wp : points) EXPECT_TRUE(wp.p.allFinite() && wp.n.allFinite());
}

TEST(WallExtractorTest, MissingArraysGiveNothing) {
  const std::vector<Eigen::Vector3f> V = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
  const std::vector<uint32_t> F = {0, 1, 2};
  WallExtractionReport report;
  report.triangles = 99;  // stale values must be reset
  EXPECT_TRUE(ExtractWallPoints({nullptr, &F}, 1, {}, &report).empty());
  EXPECT_EQ(report.triangles, 0u);
  EXPECT_TRUE(ExtractWallPoints({&V, nullptr}, 1, {}).empty());
  const std::vector<uint32_t> none;
  EXPECT_TRUE(ExtractWallPoints({&V, &none}, 1, {}).empty());
}

// Ten 10 m x 10 m walls claim 50,000 points at the default density: over a limit of
// 10,000 the mesh gives none (and allocates nothing), under it all of them.
TEST(WallExtractorTest, MeshOverThePointLimitGivesNone) {
  std::vector<Eigen::Vector3f> V;
  std::vector<uint32_t> F;
  for (uint32_t i = 0; i < 10; ++i) {
    const float x = static_cast<float>(i);
    const uint32_t b = static_cast<uint32_t>(V.size());
    V.insert(V.end(), {{x, 0, 0}, {x, 10, 0}, {x, 10, 10}, {x, 0, 10}});
    F.insert(F.end(), {b, b + 1, b + 2, b, b + 2, b + 3});
  }
  WallExtractionOptions options;
  options.max_edge_m = 20;  // the diagonals are 14 m
  options.max_points = 10000;
  WallExtractionReport report;
  EXPECT_TRUE(ExtractWallPoints({&V, &F}, 1, options, &report).empty());
  EXPECT_TRUE(report.over_limit);
  EXPECT_NEAR(report.wall_area_m2, 1000.0, 1e-6);
  options.max_points = 60000;
  EXPECT_NEAR(static_cast<double>(ExtractWallPoints({&V, &F}, 1, options, &report).size()), 50000,
              500);
  EXPECT_FALSE(report.over_limit);
}

}  // namespace
}  // namespace floorpose
