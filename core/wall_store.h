// The live wall points, keyed by mesh id (ADDED inserts, UPDATED replaces, REMOVED
// deletes), with a voxel hash over all live points. Single writer (the daemon's io
// thread); registration works on snapshots, never on the store itself.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/wall_extractor.h"

namespace floorpose {

class WallStore {
 public:
  explicit WallStore(double voxel_m = 0.05) : voxel_m_(voxel_m) {}

  // Inserts or replaces the points of a mesh. Returns the number of points now live.
  // stamp_ns: when the mesh was (re)scanned, for windowed snapshots.
  size_t Upsert(uint64_t mesh_id, std::vector<WallPoint> points, int64_t stamp_ns = 0);
  // Returns false when the id is unknown.
  bool Remove(uint64_t mesh_id);
  // The bound on memory: removes the meshes scanned longest ago (oldest stamp, then
  // lowest id), never `keep_id`, until at most max_points points are live. They are the
  // walls the registration window dropped first, and a re-scan brings them back. Returns
  // how many meshes went.
  size_t EvictOldest(size_t max_points, std::optional<uint64_t> keep_id = std::nullopt);
  bool Contains(uint64_t mesh_id) const { return meshes_.count(mesh_id) > 0; }
  // When the mesh was (re)scanned, if it is live.
  std::optional<int64_t> MeshStamp(uint64_t mesh_id) const {
    auto it = meshes_.find(mesh_id);
    return it == meshes_.end() ? std::nullopt : std::optional<int64_t>(it->second.stamp_ns);
  }
  size_t MeshPoints(uint64_t mesh_id) const {
    auto it = meshes_.find(mesh_id);
    return it == meshes_.end() ? 0 : it->second.points.size();
  }
  void Clear();

  size_t meshes() const { return meshes_.size(); }
  size_t points() const { return points_; }
  size_t occupied_voxels() const { return voxels_.size(); }
  // Points added since the counter was last taken (for scheduling registrations).
  size_t TakeNewPoints() { return std::exchange(new_points_, 0); }
  size_t new_points() const { return new_points_; }

  // One point per occupied voxel (the point of the lowest mesh id and index in it, in
  // voxel order), at most max_points (0 = all) spread evenly over the voxels: the input
  // of an update or a search. With min_stamp_ns, only meshes scanned at or after it (a
  // window that follows the SLAM drift).
  std::vector<Eigen::Vector2d> Snapshot(size_t max_points, int64_t min_stamp_ns = INT64_MIN) const;
  // Every live mesh as fn(mesh_id, points, stamp_ns), in no particular order.
  template <typename Fn>
  void ForEachMesh(Fn&& fn) const {
    for (const auto& [id, mesh] : meshes_) fn(id, mesh.points, mesh.stamp_ns);
  }
  // Live points within radius of a position (slam frame).
  std::vector<WallPoint> QueryRadius(const Eigen::Vector2f& center, float radius) const;

 private:
  struct Ref {
    uint64_t mesh_id;
    uint32_t index;
  };
  using VoxelKey = uint64_t;
  VoxelKey KeyOf(const Eigen::Vector2f& p) const;
  void IndexMesh(uint64_t mesh_id, const std::vector<WallPoint>& points);
  void UnindexMesh(uint64_t mesh_id, const std::vector<WallPoint>& points);

  double voxel_m_;
  struct Mesh {
    std::vector<WallPoint> points;
    int64_t stamp_ns = 0;
  };
  std::unordered_map<uint64_t, Mesh> meshes_;
  std::unordered_map<VoxelKey, std::vector<Ref>> voxels_;
  size_t points_ = 0;
  size_t new_points_ = 0;
};

}  // namespace floorpose
