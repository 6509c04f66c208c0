// How likely the recent wall points are under an alignment: the likelihood field of
// Probabilistic Robotics (section 6.4), one closest-wall lookup per point. A point near a
// plan wall is explained by it, with the headset's and the plan's noise; a point no plan
// wall explains is clutter (furniture, a wall the plan lacks, a mesh artefact) at a rate
// of its own, so that reality unlike the plan lowers a place's likelihood instead of
// ruling it out.
//
// The points of one window share the SLAM's drift and the plan's errors: they are worth a
// handful of independent measurements, not hundreds. The window's log-likelihood is the
// mean over its points times `independent_points` (a tempered likelihood); each window
// is taken in the share of it that is new since the last update, so overlapping windows
// do not count the same walls twice.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/closest_wall_index.h"
#include "core/se2.h"

namespace floorpose::tracking {

struct MeasurementModel {
  double sigma_m = 0.1;  // wall-point noise about a plan wall, metres
  // The share of wall points that no plan wall explains, anywhere within the index's
  // reach: clutter and walls the plan lacks.
  double clutter = 0.2;
  // What a whole window of wall points is worth in independent measurements.
  double independent_points = 5.0;

  // The mean log-likelihood of the points (slam frame) under T_plan_slam, per point.
  double MeanLogLikelihood(const std::vector<Eigen::Vector2d>& points_slam, const Se2& T_plan_slam,
                           const ClosestWallIndex& index, double reach_m) const;
  // The density of a point explained by a wall at distance d: a half-normal of sigma_m.
  double HitDensity(double d) const;
  // The log-likelihood of one point at distance d from the nearest plan wall (beyond
  // reach_m: clutter alone).
  double PointLogLikelihood(double d, double reach_m) const;
};

// At most `max_points` of the cloud, spread over it (voxels of `voxel_m`, then a stride):
// the window's evidence at a fixed cost.
std::vector<Eigen::Vector2d> ThinCloud(const std::vector<Eigen::Vector2d>& points, double voxel_m,
                                       size_t max_points);

}  // namespace floorpose::tracking
