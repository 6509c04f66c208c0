// The tracker: the alignment T_plan_slam in use, how it starts (wall pick, flip), when
// to register, whether to accept a result, and how reliable a corrected pose is. The
// daemon and the offline tools drive the same object; time is always an argument.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/closest_wall_index.h"
#include "core/registration.h"
#include "core/se2.h"

namespace floorpose {

struct TrackerOptions {
  IcpOptions icp;
  RegistrationMethod method = RegistrationMethod::kIcp;
  HoughOptions hough;
  double wall_buffer_m = 0.0;      // see RegistrationOptions
  double clip_margin_m = 0.0;      // see RegistrationOptions
  double pick_search_m = 2.5;      // correlative search after a pick or flip, metres
  double pick_search_rad = 0.175;  // ...and radians
  double jump_m = 3.0;             // a registered alignment moving the wearer further...
  double jump_rad = 0.1745;        // ...or turning more must be confirmed; 0 m: off
  double score_cap_m = 0.2;        // distances capped here in the "better fit" score
  bool local_meshes = false;       // register only meshes new since the last run (thesis "local")
  uint32_t min_new_points = 500;   // register after this many new wall points...
  double max_interval_s = 3.0;     // ...or after this long with any new points
  uint32_t min_points = 200;       // no registration on fewer points
  double reliable_rmse_m = 0.15;
  double reliable_inlier_ratio = 0.5;
};

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
enum class AlignmentSource { kNone, kWallPick, kFlip, kRegistration };

// The registration options for a run starting from an alignment of the given source:
// after a pick or flip, with the correlative search.
RegistrationOptions ToRegistrationOptions(const TrackerOptions& options, AlignmentSource from);

struct Reliability {
  ReliabilityFlag flag = ReliabilityFlag::kUnreliable;
  double probability = 0.0;  // of being within 1 m (a heuristic until calibrated)
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
  std::optional<RegistrationResult> registration;  // when source is kRegistration
};

class Tracker {
 public:
  explicit Tracker(TrackerOptions options) : options_(std::move(options)) {}

  // A new plan drops the alignment: it belonged to the old plan.
  void SetPlan(std::shared_ptr<const ClosestWallIndex> index);
  void Reset();  // drops the alignment, keeps the plan

  bool has_plan() const { return index_ != nullptr; }
  bool has_alignment() const { return alignment_.version > 0; }
  const AlignmentState& alignment() const { return alignment_; }
  const std::shared_ptr<const ClosestWallIndex>& index() const { return index_; }
  const TrackerOptions& options() const { return options_; }

  // Returns an error message, or empty on success.
  std::string ApplyWallPick(const WallPick& pick, int64_t stamp_ns);
  // Turns the alignment by 180 degrees about the last pick's plan point, or about the
  // wearer's last plan position when there was no pick (the pick's normal may face the
  // other way in the headset than on the plan).
  std::string Flip(int64_t stamp_ns);

  PlanPoseEstimate Correct(const Pose2& pose_slam);

  // Scheduling: due when aligned, with enough points, and enough new data or time.
  bool RegistrationDue(int64_t now_ns, size_t live_points, size_t new_points) const;
  void MarkRegistrationStarted(int64_t now_ns) { last_start_ns_ = now_ns; }

  struct Decision {
    bool accepted = false;
    std::string reason;
  };
  // Offers a finished registration that started from alignment `based_on_version` on
  // `cloud`. Accepted when it still applies and fits the cloud better than the alignment
  // in use (section 6.4.3).
  Decision Offer(const RegistrationResult& result, const std::vector<Eigen::Vector2d>& cloud,
                 uint64_t based_on_version, int64_t stamp_ns);

  TrackState state() const;
  Reliability CurrentReliability() const;

 private:
  void SetAlignment(const Se2& T, AlignmentSource source, int64_t stamp_ns);

  TrackerOptions options_;
  std::shared_ptr<const ClosestWallIndex> index_;
  AlignmentState alignment_;
  uint64_t next_version_ = 1;
  std::optional<Eigen::Vector2d> pick_plan_point_;
  std::optional<Eigen::Vector2d> last_plan_position_;
  std::optional<Se2> pending_jump_;  // a far result waiting for a second one to agree
  int64_t last_start_ns_ = 0;
  // Fit of the alignment in use on the latest registration cloud.
  std::optional<RegistrationResult> current_fit_;
};

const char* ToString(ReliabilityFlag flag);
const char* ToString(TrackState state);

}  // namespace floorpose
