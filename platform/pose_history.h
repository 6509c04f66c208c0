// The wearer as the engine last heard and answered them: the latest pose published where
// the wearer is now (not a late one), the headset's eye height, and the recent poses
// under the alignment they were published with, for PlanTrack.
#pragma once

#include <deque>
#include <optional>
#include <string>
#include <utility>

#include "core/frames.h"
#include "core/tracking/alignment.h"
#include "floorpose/v1/floorpose.pb.h"

namespace floorpose::platform {

class PoseHistory {
 public:
  // The newest pose: its slam height, and (once answered) the plan pose published.
  void SetEyeZ(double z) { eye_z_ = z; }
  std::optional<double> eye_z() const { return eye_z_; }
  void SetLatest(const v1::PlanPose& published) { latest_ = published; }
  const std::optional<v1::PlanPose>& latest() const { return latest_; }
  // A new plan: the latest pose was on the old one.
  void ForgetLatest() { latest_.reset(); }

  // A pose answered (late ones too), kept while its source stamp is within history_s of
  // this one's; none kept at 0.
  void Record(const Pose2& slam, const v1::PlanPose& published, double history_s);
  // The recent poses are void: the device's clock restarted, or the alignment or plan
  // they were published under went.
  void ClearTrack() { recent_.clear(); }
  // The recent poses moved under `a` (the trajectory as the alignment now says), or none.
  std::optional<v1::PlanTrack> Track(const AlignmentState& a, const std::string& floor) const;

 private:
  std::optional<double> eye_z_;
  std::optional<v1::PlanPose> latest_;
  std::deque<std::pair<Pose2, v1::PlanPose>> recent_;  // slam, as published
};

}  // namespace floorpose::platform
