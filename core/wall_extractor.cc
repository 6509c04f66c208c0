#include "core/wall_extractor.h"

#include <Eigen/Geometry>

#include <cmath>

#include "core/random.h"

namespace floorpose {

namespace {

// A vertical triangle: its corners, its horizontal normal and its area.
struct Face {
  Eigen::Vector3d v0, v1, v2;
  Eigen::Vector2f n2;
  double area;
};

// Algorithm 4.1 lines 6-8: the mesh's vertical triangles, counted in the report.
std::vector<Face> VerticalFaces(const SlamMesh& mesh, const WallExtractionOptions& options,
                                WallExtractionReport& r) {
  const auto& V = *mesh.vertices;
  const auto& F = *mesh.triangles;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  const double max_edge2 = options.max_edge_m * options.max_edge_m;
  std::vector<Face> faces;
  for (size_t t = 0; t + 2 < F.size(); t += 3) {
    ++r.triangles;
    if (F[t] >= V.size() || F[t + 1] >= V.size() || F[t + 2] >= V.size()) {
      ++r.bad_indices;
      continue;
    }
    const Eigen::Vector3d v0 = V[F[t]].cast<double>();
    const Eigen::Vector3d v1 = V[F[t + 1]].cast<double>();
    const Eigen::Vector3d v2 = V[F[t + 2]].cast<double>();
    // Algorithm 4.1 line 6.
    const Eigen::Vector3d cross = (v0 - v1).cross(v1 - v2);
    const double norm = cross.norm();
    if (!std::isfinite(norm) || norm < 1e-12 || (v0 - v1).squaredNorm() > max_edge2 ||
        (v1 - v2).squaredNorm() > max_edge2 || (v2 - v0).squaredNorm() > max_edge2) {
      ++r.degenerate_triangles;
      continue;
    }
    const Eigen::Vector3d normal = cross / norm;
    if (std::abs(normal.dot(up)) >= options.max_normal_up) continue;  // line 7
    ++r.vertical_triangles;
    const double area = 0.5 * norm;  // line 8
    r.wall_area_m2 += area;
    faces.push_back({v0, v1, v2, normal.head<2>().normalized().cast<float>(), area});
  }
  return faces;
}

// Algorithm 4.1 line 9: points on the faces at density_per_m2, those within the height
// band kept, without their height (section 4.1.1).
void SampleFaces(const std::vector<Face>& faces, const WallExtractionOptions& options,
                 SplitMix64& rng, WallExtractionReport& r, std::vector<WallPoint>& out) {
  out.reserve(static_cast<size_t>(r.wall_area_m2 * options.density_per_m2) + faces.size());
  for (const Face& f : faces) {
    const double expected = f.area * options.density_per_m2;
    size_t count = static_cast<size_t>(expected);
    if (rng.Uniform() < expected - static_cast<double>(count)) ++count;
    for (size_t j = 0; j < count; ++j) {
      // Uniform barycentric sample (Osada et al. 2002).
      const double s = std::sqrt(rng.Uniform());
      const double u = rng.Uniform();
      const Eigen::Vector3d p = (1.0 - s) * f.v0 + s * (1.0 - u) * f.v1 + s * u * f.v2;
      if (p.z() < options.min_z || p.z() > options.max_z) {
        ++r.outside_band;
        continue;
      }
      out.push_back({p.head<2>().cast<float>(), f.n2});
    }
  }
}

}  // namespace

std::vector<WallPoint> ExtractWallPoints(const SlamMesh& mesh, uint64_t mesh_id,
                                         const WallExtractionOptions& options,
                                         WallExtractionReport* report) {
  WallExtractionReport local;
  WallExtractionReport& r = report ? *report : local;
  r = {};
  std::vector<WallPoint> out;
  if (!mesh.vertices || !mesh.triangles) return out;
  // Pass 1 finds the vertical triangles and their areas; pass 2 samples them, once the
  // total is known to fit.
  const std::vector<Face> faces = VerticalFaces(mesh, options, r);
  if (options.max_points > 0 &&
      r.wall_area_m2 * options.density_per_m2 > static_cast<double>(options.max_points)) {
    r.over_limit = true;
    return out;
  }
  SplitMix64 rng(options.seed * 0x9e3779b97f4a7c15ULL ^ mesh_id);
  SampleFaces(faces, options, rng, r, out);
  return out;
}

}  // namespace floorpose
