#include "core/thin_cloud.h"

#include <algorithm>
#include <cmath>

namespace floorpose {
namespace {

// Voxel key -> slot of its point: open addressing with linear probing in a power-of-two
// table kept at most half full.
class VoxelMap {
 public:
  static constexpr uint32_t kNew = UINT32_MAX;
  // The slot of the key's voxel, or kNew after giving it `slot`.
  uint32_t Insert(uint64_t key, uint32_t slot) {
    if (key == kEmpty) {
      if (empty_key_slot_ != kNew) return empty_key_slot_;
      empty_key_slot_ = slot;
      return kNew;
    }
    if (2 * (used_ + 1) > keys_.size()) Grow();
    for (size_t i = Home(key);; i = (i + 1) & mask_) {
      if (keys_[i] == key) return slots_[i];
      if (keys_[i] == kEmpty) {
        keys_[i] = key;
        slots_[i] = slot;
        ++used_;
        return kNew;
      }
    }
  }

 private:
  static constexpr uint64_t kEmpty = ~uint64_t{0};
  size_t Home(uint64_t key) const { return (key * 0x9E3779B97F4A7C15ull) >> 20 & mask_; }
  void Grow() {
    std::vector<uint64_t> keys(std::max<size_t>(1024, 2 * keys_.size()), kEmpty);
    std::vector<uint32_t> slots(keys.size());
    keys.swap(keys_);
    slots.swap(slots_);
    mask_ = keys_.size() - 1;
    for (size_t j = 0; j < keys.size(); ++j) {
      if (keys[j] == kEmpty) continue;
      size_t i = Home(keys[j]);
      while (keys_[i] != kEmpty) i = (i + 1) & mask_;
      keys_[i] = keys[j];
      slots_[i] = slots[j];
    }
  }

  std::vector<uint64_t> keys_;
  std::vector<uint32_t> slots_;
  size_t mask_ = 0, used_ = 0;
  uint32_t empty_key_slot_ = kNew;  // the one key that is also the empty slot's mark
};

// A voxel index that stays well inside int64 whatever the coordinate.
int64_t VoxelIndex(double x, double voxel_m) {
  constexpr double kLimit = 1e15;
  return static_cast<int64_t>(std::clamp(std::floor(x / voxel_m), -kLimit, kLimit));
}

uint64_t VoxelKey(const Eigen::Vector2d& p, double voxel_m) {
  const int64_t ix = VoxelIndex(p.x(), voxel_m), iy = VoxelIndex(p.y(), voxel_m);
  return (static_cast<uint64_t>(ix) << 32) ^ static_cast<uint32_t>(iy);
}

}  // namespace

VoxelCloud VoxelMeans(const std::vector<Eigen::Vector2d>& points, double voxel_m) {
  VoxelCloud out;
  VoxelMap voxels;
  for (const Eigen::Vector2d& p : points) {
    if (!p.allFinite()) continue;
    const uint32_t slot =
        voxels.Insert(VoxelKey(p, voxel_m), static_cast<uint32_t>(out.points.size()));
    if (slot != VoxelMap::kNew) {
      out.points[slot] += p;
      ++out.counts[slot];
      continue;
    }
    out.points.push_back(p);
    out.counts.push_back(1);
  }
  for (size_t i = 0; i < out.points.size(); ++i)
    if (out.counts[i] > 1) out.points[i] /= static_cast<double>(out.counts[i]);
  return out;
}

std::vector<Eigen::Vector2d> ThinCloud(const std::vector<Eigen::Vector2d>& points, double voxel_m,
                                       size_t max_points) {
  std::vector<Eigen::Vector2d> kept;
  VoxelMap voxels;
  for (const Eigen::Vector2d& p : points)
    if (p.allFinite() && voxels.Insert(VoxelKey(p, voxel_m), 0) == VoxelMap::kNew)
      kept.push_back(p);
  if (kept.size() <= max_points || max_points == 0) return kept;
  std::vector<Eigen::Vector2d> strided;
  strided.reserve(max_points);
  const double step = static_cast<double>(kept.size()) / static_cast<double>(max_points);
  for (size_t i = 0; i < max_points; ++i)
    strided.push_back(kept[static_cast<size_t>(static_cast<double>(i) * step)]);
  return strided;
}

}  // namespace floorpose
