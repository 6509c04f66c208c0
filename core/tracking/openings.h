// Where this building has openings its plan draws closed: the map's part of the motion
// model (Probabilistic Robotics, section 5.7) learned as the wearer walks. A step through
// a plan line is priced by the odds that the line is not there where the step crosses it:
// MotionModel::through_wall for a line nobody walked through, and more once the wearer
// walked through it there under an alignment the belief trusted (a door drawn closed, a
// wall since removed). A right alignment's walk crosses only lines that are not there, and
// a wrong one crosses lines whether they are there or not: a crossing of the published
// walk, right with probability w, multiplies the odds that the line is open there by
// 1 / (1 - w).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <unordered_map>

namespace floorpose::tracking {

class Openings {
 public:
  // Crossings within about a cell of one another are of the same opening (a doorway).
  static constexpr double kCell_m = 0.5;

  explicit Openings(double through_wall = 1.0) : through_wall_(through_wall) {}

  // The probability that the plan line a step crosses at `at` (plan frame) is not there.
  double Open(const Eigen::Vector2d& at) const;
  // The published walk crossed a plan line at `at`, and was right with probability
  // `weight`.
  void Observe(const Eigen::Vector2d& at, double weight);
  size_t size() const { return open_.size(); }

 private:
  static uint64_t Key(int64_t ix, int64_t iy);

  double through_wall_;
  std::unordered_map<uint64_t, double> open_;  // of a cell a crossing opened
};

}  // namespace floorpose::tracking
