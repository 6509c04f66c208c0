// Thinning a cloud of wall points to what it tells: one point per voxel.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace floorpose {

// The mean of the points in each square voxel, in the order the voxels were first met,
// with how many of the cloud's points it stands for: a voxel's mean weighed by its count
// puts each wall's points where the whole cloud puts them, at one point per voxel.
// Non-finite points are dropped. O(n), one pass over a flat hash map.
struct VoxelCloud {
  std::vector<Eigen::Vector2d> points;
  std::vector<uint32_t> counts;
};
VoxelCloud VoxelMeans(const std::vector<Eigen::Vector2d>& points, double voxel_m);

// At most `max_points` of the cloud (0: no limit), spread over it: the first point in each
// square voxel, in the cloud's order, then every k-th of those when there are still too
// many. Non-finite points are dropped.
std::vector<Eigen::Vector2d> ThinCloud(const std::vector<Eigen::Vector2d>& points, double voxel_m,
                                       size_t max_points);

}  // namespace floorpose
