#include "platform/pose_history.h"

namespace floorpose::platform {

void PoseHistory::Record(const Pose2& slam, const v1::PlanPose& published, double history_s) {
  if (!(history_s > 0)) return;
  recent_.emplace_back(slam, published);
  const auto horizon = static_cast<int64_t>(history_s * 1e9);
  while (!recent_.empty() &&
         recent_.front().second.source_stamp_ns() < published.source_stamp_ns() - horizon)
    recent_.pop_front();
}

std::optional<v1::PlanTrack> PoseHistory::Track(const AlignmentState& a,
                                                const std::string& floor) const {
  if (recent_.empty() || a.version == 0) return std::nullopt;
  v1::PlanTrack track;
  track.set_alignment_version(a.version);
  track.set_floor(floor);
  for (const auto& [slam, published] : recent_) {
    v1::PlanPose* p = track.add_poses();
    *p = published;
    const Pose2 plan = Apply(a.T_plan_slam, slam);
    p->set_x(plan.position.x());
    p->set_y(plan.position.y());
    p->set_heading(plan.heading);
    p->set_alignment_version(a.version);
  }
  return track;
}

}  // namespace floorpose::platform
