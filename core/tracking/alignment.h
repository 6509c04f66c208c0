// The alignment T_plan_slam as the rest of floorpose sees it: how it started (a wall
// pick, a flip, a search of the plan, the belief's updates), how reliable a pose under it
// is, and what a restart needs to resume it. The estimator is core/tracking/mcl.h.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>

#include <vector>

#include "core/registration.h"
#include "core/se2.h"
#include "core/tracking/belief.h"

namespace floorpose {

// Thesis section 6.3.4: one wall point with its normal, seen by the headset (slam
// frame, horizontal part) and chosen on the plan.
struct WallPick {
  Eigen::Vector2d slam_point, slam_normal;
  Eigen::Vector2d plan_point, plan_normal;
};

// Equation 6.2 in 2D: rotate the measured normal onto the plan normal, then translate
// the measured point onto the plan point. Nothing when a normal is (near) zero.
std::optional<Se2> AlignFromWallPick(const WallPick& pick);

enum class ReliabilityFlag { kReliable, kDegraded, kUnreliable };
enum class TrackState { kWaitingForPlan, kWaitingForAlignment, kTracking, kDegraded, kLost };
enum class AlignmentSource { kNone, kWallPick, kFlip, kRegistration, kGlobalSearch };

struct Reliability {
  ReliabilityFlag flag = ReliabilityFlag::kUnreliable;
  double probability = 0.0;  // of the plan position being within 1 m
  double rmse_m = 0.0;
  std::string reason;
};

struct PlanPoseEstimate {
  Pose2 pose;  // plan frame
  uint64_t alignment_version = 0;
  Reliability reliability;
};

struct AlignmentState {
  Se2 T_plan_slam;
  uint64_t version = 0;  // 0: none yet
  AlignmentSource source = AlignmentSource::kNone;
  int64_t stamp_ns = 0;
  std::optional<RegistrationResult> registration;  // the latest polish, when it had one
};

// What a restart needs to resume the alignment where it was (platform/engine.h keeps it
// in the state snapshot): the alignment without its registration, and the belief: its
// samples, and its covariance about the wearer (what a snapshot without samples gives).
struct TrackerState {
  AlignmentState alignment;
  uint64_t next_version = 1;
  std::vector<tracking::Sample> samples;
  Eigen::Matrix3d P = Eigen::Matrix3d::Identity();  // (phi, ux, uy) about pivot
  Eigen::Vector2d pivot = Eigen::Vector2d::Zero();
  std::optional<Eigen::Vector2d> pick_plan_point;
  // The probability that the wearer is at none of the belief's places, and whether the
  // walls and a search of the plan had checked the belief (else it resumes doubted, as a
  // start).
  double elsewhere = 0.5;
  bool checked = false;
};

// The state an estimator is in: waiting for a plan or an alignment, else as its flag says.
TrackState StateOf(bool has_plan, bool has_alignment, ReliabilityFlag flag);

const char* ToString(ReliabilityFlag flag);
const char* ToString(TrackState state);

}  // namespace floorpose
