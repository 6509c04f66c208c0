// Registration of 2D wall points (slam frame) to a floor plan: one result type for every
// method (small_gicp's RegistrationResult is the model).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/closest_wall_index.h"
#include "core/se2.h"

namespace floorpose {

struct RegistrationResult {
  std::string method;
  Se2 T_plan_slam;
  bool converged = false;
  uint32_t iterations = 0;
  uint32_t points = 0;      // points given
  uint32_t matched = 0;     // points with a wall within the correspondence distance
  uint32_t inliers = 0;     // points within the inlier threshold
  double inlier_rmse = 0.0; // metres, over inliers
  double rmse = 0.0;        // metres, over matched points
  // Sum of A^T A over the last iteration's pairs, unknowns (theta, x, y) with theta
  // about the cloud's centroid; its eigenvalues (ascending) tell which directions the
  // data constrains.
  Eigen::Matrix3d normal_matrix = Eigen::Matrix3d::Zero();
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();
  double time_ms = 0.0;  // filled by the caller, which owns the clock
  std::string reason;    // why it did not converge, if it did not
};

struct IcpOptions {
  uint32_t max_iterations = 50;        // at the finest level (Algorithm 4.2 line 7)
  uint32_t levels = 2;                 // h_max
  double reject_sigma = 2.5;           // picky ICP
  double max_correspondence_m = 1.5;
  double converge_translation_m = 1e-4;
  double converge_rotation_rad = 1e-5;
  double cauchy_scale_factor = 1.0;    // 0 = plain least squares
  double inlier_threshold_m = 0.2;
};

// Point-to-line ICP after thesis Algorithm 4.2: multi-resolution (level h uses every
// 2^h-th point), picky rejection (pairs beyond reject_sigma standard deviations), Low's
// linearisation (eq. 4.4) solved about the centroid, and a Cauchy kernel whose scale
// follows the median residual. The index's max distance bounds the correspondences too.
RegistrationResult RegisterIcp(const std::vector<Eigen::Vector2d>& points_slam,
                               const ClosestWallIndex& index, const Se2& T_plan_slam_initial,
                               const IcpOptions& options);

// Fit statistics of a transform on a cloud (no optimisation): fills points, matched,
// inliers, rmse, inlier_rmse. `truncated_mse` (out, optional) is the mean of
// min(d, max_correspondence)^2 over all points: the thesis' "is the new fit better"
// score (section 6.4.3), made robust to points with no wall nearby.
void EvaluateFit(const std::vector<Eigen::Vector2d>& points_slam, const ClosestWallIndex& index,
                 const Se2& T_plan_slam, double max_correspondence_m, double inlier_threshold_m,
                 RegistrationResult* result, double* truncated_mse);

}  // namespace floorpose
