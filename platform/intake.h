// What comes in from one device, before the engine acts on it: its stamps as one forward
// timeline (DeviceClock), its poses in order, every refusal counted by kind
// (DaemonStatus.Counters) and warned about at most once a second per kind, so that bad
// input at 100 Hz cannot flood the journal.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <unordered_map>

#include "floorpose/v1/floorpose.pb.h"
#include "platform/codec.h"
#include "platform/dds.h"
#include "platform/device_clock.h"

namespace floorpose::platform {

class Intake {
 public:
  // now_ns: the daemon's clock, which paces the warnings and tells the device clock how
  // long a restart took. max_future_s: limits.max_future_s, for the refusal's text.
  Intake(DeviceClock::Options clock, double max_future_s, std::function<int64_t()> now_ns);

  // Maps an input's stamp onto the device's timeline, in place; false: refused as from
  // the future. *restarted: the device's clock started again (the stamp is taken).
  bool TakeStamp(const std::string& what, int64_t* stamp_ns, bool* restarted);

  enum class PoseOrder {
    kNewest,     // the newest pose so far: the wearer is there now
    kLate,       // older than the newest: answered, but not walked backwards
    kDuplicate,  // the newest again: answered already, dropped
  };
  // Where a pose's timeline stamp stands among those taken (counted and warned about).
  PoseOrder TakePose(int64_t stamp_ns, int64_t source_stamp_ns);
  std::optional<int64_t> newest_pose_ns() const { return newest_pose_ns_; }

  // A refused input: counted by kind and warned about.
  void Reject(Refusal kind, const std::string& why);
  // A warning, at most one line a second per topic (the next says how many were held back).
  void Warn(const std::string& topic, const std::string& line);
  // Samples of `topic` DDS lost or rejected before they reached us.
  void OnDdsLosses(Topic topic, uint64_t lost, uint64_t rejected);

  v1::DaemonStatus::Counters& counters() { return counters_; }
  const v1::DaemonStatus::Counters& counters() const { return counters_; }
  DeviceClock& clock() { return clock_; }
  const DeviceClock& clock() const { return clock_; }

 private:
  struct Throttle {
    int64_t next_ns = 0;
    uint64_t held_back = 0;
  };
  std::function<int64_t()> now_ns_;
  double max_future_s_;
  // Every stamp below is on its timeline, except the source stamps of published poses.
  // Its newest stamp is the engine's scheduling clock.
  DeviceClock clock_;
  std::optional<int64_t> newest_pose_ns_;
  std::unordered_map<std::string, Throttle> throttles_;
  v1::DaemonStatus::Counters counters_;
};

}  // namespace floorpose::platform
