#include "platform/intake.h"

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

namespace floorpose::platform {

Intake::Intake(DeviceClock::Options clock, double max_future_s, std::function<int64_t()> now_ns)
    : now_ns_(std::move(now_ns)), max_future_s_(max_future_s), clock_(clock) {}

bool Intake::TakeStamp(const std::string& what, int64_t* stamp_ns, bool* restarted) {
  *restarted = false;
  const DeviceClock::Mapped m = clock_.Take(*stamp_ns, now_ns_());
  switch (m.verdict) {
    case DeviceClock::Verdict::kFuture:
      Reject(Refusal::kFuture,
             fmt::format("{} of {} ns is more than limits.max_future_s ({} s) ahead of the newest "
                         "stamp taken: from the future",
                         what, *stamp_ns, max_future_s_));
      return false;
    case DeviceClock::Verdict::kRestarted:
      counters_.set_clock_restarts(counters_.clock_restarts() + 1);
      Warn("clock restart",
           fmt::format("{} of {} ns is {:.1f} s off the headset's clock: the clock started again "
                       "(app restarted); ordering starts again, alignment and walls kept",
                       what, *stamp_ns, -1e-9 * static_cast<double>(m.fell_back_ns)));
      *restarted = true;
      break;
    case DeviceClock::Verdict::kTaken: break;
  }
  *stamp_ns = m.timeline_ns;
  return true;
}

Intake::PoseOrder Intake::TakePose(int64_t stamp_ns, int64_t source_stamp_ns) {
  if (newest_pose_ns_ && stamp_ns == *newest_pose_ns_) {
    counters_.set_duplicate_stamps(counters_.duplicate_stamps() + 1);
    Warn("duplicate pose",
         "pose of " + std::to_string(source_stamp_ns) + " ns again: dropped (answered already)");
    return PoseOrder::kDuplicate;
  }
  if (newest_pose_ns_ && stamp_ns < *newest_pose_ns_) {
    counters_.set_stale_stamps(counters_.stale_stamps() + 1);
    Warn("stale pose",
         fmt::format("pose of {} ns is {:.3f} s older than the newest taken: not tracked",
                     source_stamp_ns, 1e-9 * static_cast<double>(*newest_pose_ns_ - stamp_ns)));
    return PoseOrder::kLate;
  }
  newest_pose_ns_ = stamp_ns;
  return PoseOrder::kNewest;
}

void Intake::Warn(const std::string& topic, const std::string& line) {
  Throttle& t = throttles_[topic];
  const int64_t now = now_ns_();
  if (now < t.next_ns) {
    ++t.held_back;
    return;
  }
  if (t.held_back > 0)
    spdlog::warn("{} ({} more like it in the last second)", line, t.held_back);
  else
    spdlog::warn("{}", line);
  t.held_back = 0;
  t.next_ns = now + 1'000'000'000;
}

void Intake::Reject(Refusal kind, const std::string& why) {
  auto& c = counters_;
  c.set_rejected_messages(c.rejected_messages() + 1);
  switch (kind) {
    case Refusal::kMalformed: c.set_malformed(c.malformed() + 1); break;
    case Refusal::kUnknownEnum: c.set_unknown_enum_values(c.unknown_enum_values() + 1); break;
    case Refusal::kNonFinite: c.set_non_finite(c.non_finite() + 1); break;
    case Refusal::kOutOfRange: c.set_out_of_range(c.out_of_range() + 1); break;
    case Refusal::kOverLimits: c.set_over_limits(c.over_limits() + 1); break;
    case Refusal::kInconsistent: c.set_inconsistent(c.inconsistent() + 1); break;
    case Refusal::kFuture: c.set_future_stamps(c.future_stamps() + 1); break;
  }
  Warn("rejected " + std::to_string(static_cast<int>(kind)), "rejected: " + why);
}

void Intake::OnDdsLosses(Topic topic, uint64_t lost, uint64_t rejected) {
  if (lost + rejected == 0) return;
  counters_.set_samples_lost(counters_.samples_lost() + lost);
  counters_.set_samples_rejected(counters_.samples_rejected() + rejected);
  Warn(std::string("dds ") + TopicName(topic),
       fmt::format("DDS lost {} and rejected {} samples of {} before they reached floorposed "
                   "(a sample too large or a reader over its limits)",
                   lost, rejected, TopicName(topic)));
}

}  // namespace floorpose::platform
