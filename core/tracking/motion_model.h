// How the SLAM frame drifts against the plan as the wearer walks and turns: the motion
// model of Monte Carlo localization over the alignment T_plan_slam (Probabilistic
// Robotics, section 5.4, with the SLAM's drift in place of wheel slip). The alignment is
// fixed while the SLAM is right; each metre walked and each radian turned adds a random
// walk to it, taken about the wearer, where the drift shows.
#pragma once

#include <Eigen/Core>

#include <vector>

#include "core/closest_wall_index.h"
#include "core/random.h"
#include "core/se2.h"

namespace floorpose::tracking {

struct MotionModel {
  // Standard deviation of the alignment's position at the wearer per square root of a
  // metre walked (a random walk: 0.06 m/sqrt(m) is 0.6 m after 100 m), metres.
  double position_m_per_sqrt_m = 0.06;
  // ...of its heading, radians per square root of a metre walked.
  double heading_rad_per_sqrt_m = 0.3 * M_PI / 180;
  // ...and per radian turned: the SLAM's error measuring its own turning, a fraction.
  double heading_per_turn = 0.005;
  // A headset that loses tracking relocalizes in a frame that may have jumped: poses that
  // stop for longer than lost_after_s (or say so) spread the alignment by this much at the
  // wearer, metres and radians (one standard deviation), and the wall points from before
  // are of the old frame.
  double lost_after_s = 1.5;
  double relocalization_m = 1.0;
  double relocalization_rad = 10.0 * M_PI / 180;
  // The map's part of the motion model (Probabilistic Robotics, section 5.7): a wearer
  // walks through a plan line only where the line is not there (a door drawn closed, a
  // wall since removed); the probability of that, per line walked through.
  double through_wall = 0.1;

  // Standard deviations (heading rad, position m) of the drift of a walk of `metres`
  // with `turned_rad` of turning.
  Eigen::Vector2d Sigmas(double metres, double turned_rad) const;

  // A sample of T moved by that drift, turned and shifted about `pivot` (plan frame: the
  // wearer), with `sigmas` as Sigmas gives them.
  Se2 Sample(const Se2& T, const Eigen::Vector2d& pivot, const Eigen::Vector2d& sigmas,
             SplitMix64& rng) const;

  // The log-probability of the wearer's path (slam frame, in order) under T: through_wall
  // for every step that crosses a plan wall.
  double PathLogPrior(const std::vector<Eigen::Vector2d>& path_slam, const Se2& T,
                      const ClosestWallIndex& index) const;
};

}  // namespace floorpose::tracking
