#include "core/tracking/alignment.h"

#include <cmath>

namespace floorpose {

std::optional<Se2> AlignFromWallPick(const WallPick& pick) {
  if (!pick.slam_normal.allFinite() || !pick.plan_normal.allFinite() ||
      !pick.slam_point.allFinite() || !pick.plan_point.allFinite() ||
      pick.slam_normal.norm() < 1e-6 || pick.plan_normal.norm() < 1e-6) {
    return std::nullopt;
  }
  // theta = angle from n_measure to n_ref (eq. 6.2; in 2D the axis is always z).
  Se2 T;
  T.theta = WrapAngle(std::atan2(pick.plan_normal.y(), pick.plan_normal.x()) -
                      std::atan2(pick.slam_normal.y(), pick.slam_normal.x()));
  T.t = pick.plan_point - T.R() * pick.slam_point;  // T = x_ref - R x_measure
  return T;
}

TrackState StateOf(bool has_plan, bool has_alignment, ReliabilityFlag flag) {
  if (!has_plan) return TrackState::kWaitingForPlan;
  if (!has_alignment) return TrackState::kWaitingForAlignment;
  switch (flag) {
    case ReliabilityFlag::kReliable: return TrackState::kTracking;
    case ReliabilityFlag::kDegraded: return TrackState::kDegraded;
    case ReliabilityFlag::kUnreliable: return TrackState::kLost;
  }
  return TrackState::kLost;
}

const char* ToString(ReliabilityFlag flag) {
  switch (flag) {
    case ReliabilityFlag::kReliable: return "RELIABLE";
    case ReliabilityFlag::kDegraded: return "DEGRADED";
    case ReliabilityFlag::kUnreliable: return "UNRELIABLE";
  }
  return "?";
}

const char* ToString(TrackState state) {
  switch (state) {
    case TrackState::kWaitingForPlan: return "WAITING_FOR_PLAN";
    case TrackState::kWaitingForAlignment: return "WAITING_FOR_ALIGNMENT";
    case TrackState::kTracking: return "TRACKING";
    case TrackState::kDegraded: return "DEGRADED";
    case TrackState::kLost: return "LOST";
  }
  return "?";
}

}  // namespace floorpose
