// How likely the recent wall points are under an alignment: the likelihood field of
// Probabilistic Robotics (section 6.4), one closest-wall lookup per point. A point near a
// plan wall is explained by it, with the headset's and the plan's noise; a point no plan
// wall explains is clutter (furniture, a wall the plan lacks, a mesh artefact) at a rate
// of its own, so that reality unlike the plan lowers a place's likelihood instead of
// ruling it out.
//
// The points of one window share the SLAM's drift and the plan's errors: they are worth a
// handful of independent measurements, not hundreds. The window's log-likelihood is the
// mean over its points times `independent_points` (a tempered likelihood); each update
// takes the window's share that is new since the last (RunMclUpdate), on the walls new
// since then, so overlapping windows do not count the same walls twice.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/closest_wall_index.h"
#include "core/se2.h"

namespace floorpose::tracking {

struct MeasurementModel {
  double sigma_m = 0.1;  // wall-point noise about a plan wall, metres
  // Where the plan and the building disagree, as a share: of the wall points, those no
  // plan wall explains, anywhere within the index's reach (clutter, walls the plan
  // lacks); of the plan walls in sight of the wearer, those no wall point shows (glass,
  // walls since removed, doors drawn closed).
  double clutter = 0.2;
  // What a whole window of wall points is worth in independent measurements.
  double independent_points = 5.0;

  // The mean log-likelihood of the points (slam frame) under T_plan_slam, per point: of
  // PointLogLikelihood tabulated (within 3e-6 a point), and exact where it is clutter's.
  double MeanLogLikelihood(const std::vector<Eigen::Vector2d>& points_slam, const Se2& T_plan_slam,
                           const ClosestWallIndex& index, double reach_m) const;
  // The density of a point explained by a wall at distance d: a half-normal of sigma_m.
  double HitDensity(double d) const;
  // The log-likelihood of one point at distance d from the nearest plan wall (beyond
  // reach_m: clutter alone).
  double PointLogLikelihood(double d, double reach_m) const;
  // The distance from which PointLogLikelihood is clutter's alone to the last bit: the
  // hit density falls below 2^-55 of the clutter density (half a unit in the last place
  // is at least 2^-54 of it), so adding it rounds to nothing. MeanLogLikelihood needs no
  // closest wall for a point it knows is at least this far.
  double ClutterOnlyFromM(double reach_m) const;
};

// What the wearer had in sight (Probabilistic Robotics 6.3: the beam model's view, which
// also counts what is not there): from where the wearer stood, the nearest wall within
// kSightM (none: at kSightM) is as far on the plan as in the mesh, within kSeenMarginM
// (a door's jambs, thinning), unless the plan and the building disagree there. So a place
// that puts plan walls beside the walk where the mesh shows none, or open floor where
// the mesh shows walls, is less likely, not ruled out. The mesh around a position comes
// within kMeshLatencyS, so only positions that old are asked.
constexpr double kSightM = 2.0;
constexpr double kSeenMarginM = 0.5;
constexpr double kMeshLatencyS = 5.0;
// A wearer is never nearer a real wall than this: a position that near a plan wall is a
// walk through it, which the motion model prices (through_wall), so it is not asked.
constexpr double kBodyM = 0.3;

// For each wearer position (slam), the distance to the nearest wall point (slam).
std::vector<double> NearestWallPoint(const std::vector<Eigen::Vector2d>& positions,
                                     const std::vector<Eigen::Vector2d>& points);
// What was in sight under T: the sum of the log-likelihoods of the positions asked (the
// plan's nearest wall and the mesh's disagree at `model.clutter`, agree at 1 - clutter).
struct SightFit {
  double log_likelihood = 0;
  size_t asked = 0;
  // Per position asked, 0 when none was.
  double Mean() const { return asked == 0 ? 0.0 : log_likelihood / static_cast<double>(asked); }
};
SightFit SightLogLikelihood(const MeasurementModel& model,
                            const std::vector<Eigen::Vector2d>& positions_slam,
                            const std::vector<double>& nearest_point, const Se2& T_plan_slam,
                            const ClosestWallIndex& index);

}  // namespace floorpose::tracking
