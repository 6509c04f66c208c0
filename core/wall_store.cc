#include "core/wall_store.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

namespace floorpose {

WallStore::VoxelKey WallStore::KeyOf(const Eigen::Vector2f& p) const {
  const auto ix = static_cast<int32_t>(std::floor(p.x() / voxel_m_));
  const auto iy = static_cast<int32_t>(std::floor(p.y() / voxel_m_));
  return (static_cast<uint64_t>(static_cast<uint32_t>(ix)) << 32) | static_cast<uint32_t>(iy);
}

void WallStore::IndexMesh(uint64_t mesh_id, const std::vector<WallPoint>& points) {
  for (uint32_t i = 0; i < points.size(); ++i) voxels_[KeyOf(points[i].p)].push_back({mesh_id, i});
}

void WallStore::UnindexMesh(uint64_t mesh_id, const std::vector<WallPoint>& points) {
  for (const WallPoint& wp : points) {
    auto it = voxels_.find(KeyOf(wp.p));
    if (it == voxels_.end()) continue;
    auto& refs = it->second;
    refs.erase(std::remove_if(refs.begin(), refs.end(),
                              [&](const Ref& r) { return r.mesh_id == mesh_id; }),
               refs.end());
    if (refs.empty()) voxels_.erase(it);
  }
}

size_t WallStore::Upsert(uint64_t mesh_id, std::vector<WallPoint> points, int64_t stamp_ns) {
  // Non-finite points never enter the store.
  points.erase(
      std::remove_if(points.begin(), points.end(),
                     [](const WallPoint& w) { return !w.p.allFinite() || !w.n.allFinite(); }),
      points.end());
  auto it = meshes_.find(mesh_id);
  if (it != meshes_.end()) {
    UnindexMesh(mesh_id, it->second.points);
    points_ -= it->second.points.size();
    it->second.points = std::move(points);
  } else {
    it = meshes_.emplace(mesh_id, Mesh{std::move(points), 0}).first;
  }
  it->second.stamp_ns = stamp_ns;
  IndexMesh(mesh_id, it->second.points);
  points_ += it->second.points.size();
  new_points_ += it->second.points.size();
  return points_;
}

bool WallStore::Remove(uint64_t mesh_id) {
  auto it = meshes_.find(mesh_id);
  if (it == meshes_.end()) return false;
  UnindexMesh(mesh_id, it->second.points);
  points_ -= it->second.points.size();
  meshes_.erase(it);
  return true;
}

size_t WallStore::EvictOldest(size_t max_points, std::optional<uint64_t> keep_id) {
  if (points_ <= max_points) return 0;
  std::vector<std::pair<int64_t, uint64_t>> by_age;  // (stamp, id)
  by_age.reserve(meshes_.size());
  for (const auto& [id, mesh] : meshes_)
    if (id != keep_id) by_age.emplace_back(mesh.stamp_ns, id);
  std::sort(by_age.begin(), by_age.end());
  size_t evicted = 0;
  for (const auto& [stamp, id] : by_age) {
    if (points_ <= max_points) break;
    Remove(id);
    ++evicted;
  }
  return evicted;
}

void WallStore::Clear() {
  meshes_.clear();
  voxels_.clear();
  points_ = 0;
  new_points_ = 0;
}

std::vector<Eigen::Vector2d> WallStore::Snapshot(size_t max_points, int64_t min_stamp_ns) const {
  // One point per voxel, the first of the lowest mesh id, in sorted voxel order: the
  // snapshot is independent of hash-map iteration order, so that the daemon and the
  // offline evaluator register the same points.
  std::vector<std::pair<VoxelKey, const WallPoint*>> cells;
  if (min_stamp_ns != INT64_MIN) {
    // A window: from its meshes alone, not every voxel of the store.
    std::vector<std::tuple<VoxelKey, uint64_t, uint32_t>> refs;
    for (const auto& [id, mesh] : meshes_) {
      if (mesh.stamp_ns < min_stamp_ns) continue;
      for (uint32_t i = 0; i < mesh.points.size(); ++i)
        refs.emplace_back(KeyOf(mesh.points[i].p), id, i);
    }
    std::sort(refs.begin(), refs.end());
    for (size_t i = 0; i < refs.size(); ++i) {
      const auto& [key, id, index] = refs[i];
      if (i == 0 || std::get<0>(refs[i - 1]) != key)
        cells.emplace_back(key, &meshes_.at(id).points[index]);
    }
  } else {
    cells.reserve(voxels_.size());
    for (const auto& [key, refs] : voxels_) {
      const Ref* best = nullptr;
      for (const Ref& r : refs)
        if (!best || std::tie(r.mesh_id, r.index) < std::tie(best->mesh_id, best->index)) best = &r;
      if (best) cells.emplace_back(key, &meshes_.at(best->mesh_id).points[best->index]);
    }
    std::sort(cells.begin(), cells.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
  }
  const size_t n = cells.size();
  const size_t take = (max_points == 0 || max_points >= n) ? n : max_points;
  std::vector<Eigen::Vector2d> out;
  out.reserve(take);
  for (size_t k = 0; k < take; ++k) out.push_back(cells[k * n / take].second->p.cast<double>());
  return out;
}

std::vector<WallPoint> WallStore::QueryRadius(const Eigen::Vector2f& c, float radius) const {
  std::vector<WallPoint> out;
  const int r = static_cast<int>(std::ceil(radius / voxel_m_));
  const auto cx = static_cast<int32_t>(std::floor(c.x() / voxel_m_));
  const auto cy = static_cast<int32_t>(std::floor(c.y() / voxel_m_));
  for (int dx = -r; dx <= r; ++dx) {
    for (int dy = -r; dy <= r; ++dy) {
      const uint64_t key = (static_cast<uint64_t>(static_cast<uint32_t>(cx + dx)) << 32) |
                           static_cast<uint32_t>(cy + dy);
      auto it = voxels_.find(key);
      if (it == voxels_.end()) continue;
      for (const Ref& ref : it->second) {
        const WallPoint& wp = meshes_.at(ref.mesh_id).points[ref.index];
        if ((wp.p - c).squaredNorm() <= radius * radius) out.push_back(wp);
      }
    }
  }
  return out;
}

}  // namespace floorpose
