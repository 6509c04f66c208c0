// Thesis Algorithm 4.1: mesh to 2D wall points with normals.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace floorpose {

struct WallPoint {
  Eigen::Vector2f p;  // slam frame, metres
  Eigen::Vector2f n;  // unit normal of the wall face in the horizontal plane
};

struct WallExtractionOptions {
  double max_normal_up = 0.1;    // |n . up| below this is a vertical face (Alg. 4.1 line 7)
  double density_per_m2 = 50.0;  // points per square metre of wall face
  uint64_t seed = 1;
  double max_edge_m = 10.0;  // longer edges are corrupt input
  // A mesh that would give more points than this gives none (report.over_limit): memory
  // stays bounded whatever the triangles claim. 0 = no limit.
  size_t max_points = 200000;
  // Keep only points in this height band (slam z, metres): above the furniture, desks and
  // people that are not on the plan, below the ceiling. The daemon sets it from the
  // wearer's eye height; the default keeps everything.
  double min_z = -std::numeric_limits<double>::infinity();
  double max_z = std::numeric_limits<double>::infinity();
};

// A mesh already in the slam frame (right-handed, Z up, world coordinates).
struct SlamMesh {
  const std::vector<Eigen::Vector3f>* vertices = nullptr;
  const std::vector<uint32_t>* triangles = nullptr;  // 3 indices a triangle
};

struct WallExtractionReport {
  size_t triangles = 0;
  size_t vertical_triangles = 0;
  size_t degenerate_triangles = 0;  // zero area, non-finite or too long
  size_t bad_indices = 0;
  double wall_area_m2 = 0.0;
  bool over_limit = false;  // the expected point count exceeded max_points
  size_t outside_band = 0;  // sampled points dropped by the height band
};

// Samples points on the vertical triangles, their number proportional to area: each
// triangle gets floor(A d) points and one more with probability frac(A d), so that
// small triangles are not lost. Deterministic for a given (seed, mesh_id). Unlike the
// thesis' two-step interpolation (which crowds points at the third vertex), points are
// uniform over the triangle.
std::vector<WallPoint> ExtractWallPoints(const SlamMesh& mesh, uint64_t mesh_id,
                                         const WallExtractionOptions& options,
                                         WallExtractionReport* report = nullptr);

}  // namespace floorpose
