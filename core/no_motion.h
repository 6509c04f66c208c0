// The no-motion alert of a PASS device (NFPA 1982), from the headset's own positions: the
// head staying within `motion_m` of where it was for `pre_alert_s` is a pre-alert, for
// `no_motion_s` the alert. Moving out of that radius ends both; an acknowledgement marks
// the episode seen until it ends. Headset time only: it needs no plan and no alignment.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>

namespace floorpose {

struct NoMotionOptions {
  double motion_m = 0.3;
  double pre_alert_s = 20.0;
  double no_motion_s = 30.0;
};

class NoMotionAlarm {
 public:
  enum class Level { kNone, kPreAlert, kAlert };
  explicit NoMotionAlarm(const NoMotionOptions& options = {}) : options_(options) {}

  // The head at `position` (slam metres) at `stamp_ns`. Returns true when the level or the
  // acknowledgement changed.
  bool Update(int64_t stamp_ns, const Eigen::Vector3d& position);
  // Returns false when there is no alert to acknowledge.
  bool Acknowledge(const std::string& by);
  void Reset();

  Level level() const { return level_; }
  bool acknowledged() const { return acknowledged_; }
  const std::string& acknowledged_by() const { return acknowledged_by_; }
  double still_s() const;  // how long the head has been within motion_m, as of the latest update
  int64_t still_since_ns() const { return anchor_ns_; }

 private:
  NoMotionOptions options_;
  bool started_ = false;
  Eigen::Vector3d anchor_ = Eigen::Vector3d::Zero();  // where the head came to rest
  int64_t anchor_ns_ = 0, latest_ns_ = 0;
  Level level_ = Level::kNone;
  bool acknowledged_ = false;
  std::string acknowledged_by_;
};

}  // namespace floorpose
