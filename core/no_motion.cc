#include "core/no_motion.h"

namespace floorpose {

bool NoMotionAlarm::Update(int64_t stamp_ns, const Eigen::Vector3d& position) {
  if (!position.allFinite()) return false;
  const Level level_before = level_;
  const bool acknowledged_before = acknowledged_;
  if (!started_ || (position - anchor_).norm() > options_.motion_m || stamp_ns < anchor_ns_) {
    // Moved (or the first pose, or a clock that went back): the stillness starts again here.
    started_ = true;
    anchor_ = position;
    anchor_ns_ = stamp_ns;
    acknowledged_ = false;
    acknowledged_by_.clear();
  }
  latest_ns_ = stamp_ns;
  const double still = still_s();
  level_ = still >= options_.no_motion_s   ? Level::kAlert
           : still >= options_.pre_alert_s ? Level::kPreAlert
                                           : Level::kNone;
  return level_ != level_before || acknowledged_ != acknowledged_before;
}

bool NoMotionAlarm::Acknowledge(const std::string& by) {
  if (level_ == Level::kNone) return false;
  acknowledged_ = true;
  acknowledged_by_ = by;
  return true;
}

void NoMotionAlarm::Reset() { *this = NoMotionAlarm(options_); }

double NoMotionAlarm::still_s() const {
  return started_ ? static_cast<double>(latest_ns_ - anchor_ns_) * 1e-9 : 0.0;
}

}  // namespace floorpose
