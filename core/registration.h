// Registration of 2D wall points (slam frame) to a floor plan: one result type for every
// method (small_gicp's RegistrationResult is the model).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/closest_wall_index.h"
#include "core/se2.h"

namespace floorpose {

// Two fits are different places when they put the wall points this far apart across
// their walls (RMS, metres).
inline constexpr double kDistinctShiftM = 0.3;

struct RegistrationResult {
  std::string method;
  Se2 T_plan_slam;
  bool converged = false;
  uint32_t iterations = 0;
  uint32_t points = 0;       // points given
  uint32_t matched = 0;      // points with a wall within the correspondence distance
  uint32_t inliers = 0;      // points within the inlier threshold
  double inlier_rmse = 0.0;  // metres, over inliers
  double rmse = 0.0;         // metres, over matched points
  // Sum of A^T A over the last iteration's pairs, unknowns (theta, x, y) with theta
  // about the cloud's centroid; its eigenvalues (ascending) tell which directions the
  // data constrains.
  Eigen::Matrix3d normal_matrix = Eigen::Matrix3d::Zero();
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();
  // Unit eigenvectors (columns, ascending) of the normal matrix with theta scaled by the
  // cloud's radius, and those the data leaves unconstrained (solution remapping, Zhang
  // and Singh 2016): the solution did not move along them.
  Eigen::Matrix3d eigenvectors = Eigen::Matrix3d::Identity();
  std::vector<Eigen::Vector3d> degenerate_directions;
  // With a correlative search: the best fit's score over the best other place's (one
  // that moves the fitting points over kDistinctShiftM across their walls, see
  // WallNormalShift), in (0, 1]; near 1, two
  // places explain the walls equally well. 0 when there was no search or no other fit.
  double ambiguity = 0.0;
  double time_ms = 0.0;  // filled by the caller, which owns the clock
  std::string reason;    // why it did not converge, if it did not
};

struct IcpOptions {
  uint32_t max_iterations = 50;  // at the finest level (Algorithm 4.2 line 7)
  uint32_t levels = 2;           // h_max, at least
  // More levels when needed so the coarsest uses at most this many points: large clouds
  // converge on a subset and the full cloud only polishes (one or two iterations).
  uint32_t coarsest_points = 1000;
  double reject_sigma = 2.5;  // picky ICP
  double max_correspondence_m = 1.5;
  double converge_translation_m = 3e-4;
  double converge_rotation_rad = 3e-5;
  double cauchy_scale_factor = 1.0;  // 0 = plain least squares
  double inlier_threshold_m = 0.2;
  // A direction is degenerate when its eigenvalue is below this share of the total
  // weight of the pairs (theta measured as arc length at the cloud's RMS radius, so
  // rotation and translation compare). 0 disables solution remapping.
  double degeneracy_ratio = 0.01;
  // The cloud is registered on the mean of each square voxel of this size, weighing as all
  // the voxel's points (0: every point): the cost grows with the walls seen rather than
  // with how densely they were sampled. The config's default (icp.voxel_m).
  double voxel_m = 0;
};

enum class RegistrationMethod { kIcp, kIk, kHough };
const char* ToString(RegistrationMethod method);
bool ParseRegistrationMethod(const std::string& name, RegistrationMethod* method);

struct HoughOptions {
  // The config's defaults (35 and 0.15 degrees, config.proto), so that tools and daemon agree.
  double max_rotation_rad = 35.0 * M_PI / 180.0;  // search +-this about the initial rotation
  double bin_rad = 0.15 * M_PI / 180.0;           // histogram resolution
  double smooth_rad = 0.01;                       // Gaussian smoothing of both histograms
};

// The options the thesis varies (section 6.4.3) plus the method's own.
struct RegistrationOptions {
  RegistrationMethod method = RegistrationMethod::kIcp;
  IcpOptions icp;  // iteration, rejection, kernel and degeneracy settings of every method
  HoughOptions hough;
  // Keep only points within this distance of a plan wall under the initial transform
  // (the thesis' buffer, 0 or 0.5 m); 0 keeps all.
  double wall_buffer_m = 0.0;
  // Clip the plan to the box of the points (under the initial guess) grown by this
  // margin before registering (the thesis' 2 m); 0 registers against the whole plan.
  // With the O(1) index this buys no speed; it is here to reproduce the thesis.
  double clip_margin_m = 0.0;
  // Correlative search before refining (as real-time correlative scan matching in
  // Cartographer, Hess et al. 2016): translations within +-search_window_m and rotations
  // within +-search_window_rad of the initial guess are scored on a point subset, and
  // the method refines the best few (and the initial guess); the best fit wins. Needed
  // when the guess can be metres off (a wall pick); 0 skips it.
  double search_window_m = 0.0;
  double search_window_rad = 0.0;
  // Rotations of the search turn about this plan point: where the guess is known best (a
  // wall pick's point, whose error a heading error swings into metres at the wearer).
  // Without it, about the cloud's centroid.
  std::optional<Eigen::Vector2d> search_pivot;
  // With a covariance of the guess about search_pivot (unknowns: the rotation phi about
  // the pivot, then the shift ux, uy), only corrections within search_max_sigmas of it
  // are searched: the box shrinks to the ellipse (a hall's open axis, not across its
  // walls).
  std::optional<Eigen::Matrix3d> search_covariance;
  double search_max_sigmas = 3.0;
  uint32_t search_candidates = 4;
  // Refined places scoring within this ratio of the best (0.9: 10% worse) are told apart
  // by the initial guess: the nearest wins. 0 = the best score always wins.
  double search_tie_ratio = 0.0;
};

// Point-to-line ICP after thesis Algorithm 4.2: multi-resolution (level h uses every
// 2^h-th point), picky rejection (pairs beyond reject_sigma standard deviations), Low's
// linearisation (eq. 4.4) solved about the centroid, and a Cauchy kernel whose scale
// follows the median residual. The index's max distance bounds the correspondences too.
// With IcpOptions::voxel_m the cloud is first thinned to its voxels' means, each weighing
// as its voxel's points; the counts in the result are the cloud's.
RegistrationResult RegisterIcp(const std::vector<Eigen::Vector2d>& points_slam,
                               const ClosestWallIndex& index, const Se2& T_plan_slam_initial,
                               const IcpOptions& options);

// Instantaneous kinematics after Pottmann et al. 2004 (thesis Algorithms 4.3 to 4.5) in
// 2D: the velocity field v(x) = c_bar + omega J x minimising the local quadratic
// approximants of the squared distance (point-to-line for a segment's interior,
// point-to-point at its ends), turned into the rigid rotation by omega about the
// instantaneous centre (the 2D Pluecker axis), applied only when it fits better
// (Alg. 4.3 line 9), with step halving otherwise.
RegistrationResult RegisterIk(const std::vector<Eigen::Vector2d>& points_slam,
                              const ClosestWallIndex& index, const Se2& T_plan_slam_initial,
                              const IcpOptions& options);

// Thesis Algorithm 4.6 alone: the rotation (plan frame, within +-h.max_rotation_rad) that
// best lines the histogram of the cloud's wall normals under `initial` up with that of
// the plan's walls near it (modulo pi: walls have two faces). It needs no position, only
// wall directions. Nothing without normals or when nothing correlates.
std::optional<double> HoughRotation(const std::vector<Eigen::Vector2d>& points_slam,
                                    const std::vector<Eigen::Vector2d>& normals_slam,
                                    const ClosestWallIndex& index, const Se2& T_plan_slam_initial,
                                    const HoughOptions& hough);

// Thesis Algorithms 4.6 and 4.7: the rotation from the histogram of point normal angles
// correlated with the plan's wall angles (weighted by length, modulo pi since walls have
// two faces), then translation-only ICP (point-to-line, a 2x2 solve per iteration).
RegistrationResult RegisterHough(const std::vector<Eigen::Vector2d>& points_slam,
                                 const std::vector<Eigen::Vector2d>& normals_slam,
                                 const ClosestWallIndex& index, const Se2& T_plan_slam_initial,
                                 const IcpOptions& icp, const HoughOptions& hough);

// The correlative search of RegistrationOptions::search_window_*: the best few starting
// transforms (T_plan_slam) around the initial guess, best first.
std::vector<Se2> CorrelativeSearch(const std::vector<Eigen::Vector2d>& points_slam,
                                   const ClosestWallIndex& index, const Se2& T_plan_slam_initial,
                                   const RegistrationOptions& options);

// Runs the chosen method, after the wall buffer. normals_slam may be empty except for
// Hough.
RegistrationResult Register(const std::vector<Eigen::Vector2d>& points_slam,
                            const std::vector<Eigen::Vector2d>& normals_slam,
                            const ClosestWallIndex& index, const Se2& T_plan_slam_initial,
                            const RegistrationOptions& options);

// How far T_b moves the points that fit a wall under T_a (within the inlier threshold)
// across their walls: the RMS of the shift along each wall's normal, metres. Small when
// the two differ only along the walls (a corridor slid along its axis).
double WallNormalShift(const std::vector<Eigen::Vector2d>& points_slam,
                       const ClosestWallIndex& index, const Se2& T_a, const Se2& T_b,
                       double inlier_threshold_m);

// Fit statistics of a transform on a cloud (no optimisation): fills points, matched,
// inliers, rmse, inlier_rmse. `truncated_mse` (out, optional) is the mean of
// min(d, max_correspondence)^2 over all points: the thesis' "is the new fit better"
// score (section 6.4.3), made robust to points with no wall nearby.
void EvaluateFit(const std::vector<Eigen::Vector2d>& points_slam, const ClosestWallIndex& index,
                 const Se2& T_plan_slam, double max_correspondence_m, double inlier_threshold_m,
                 RegistrationResult* result, double* truncated_mse);

}  // namespace floorpose
