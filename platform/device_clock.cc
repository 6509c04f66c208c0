#include "platform/device_clock.h"

#include <algorithm>
#include <limits>

namespace floorpose::platform {
namespace {

// Stamps are within +-2^62 ns (the codec refuses others), so their differences need more
// than 64 bits; what goes back to int64 is clamped (reached only by absurd stamps).
__extension__ typedef __int128 Wide;

int64_t Clamp(Wide v) {
  constexpr int64_t lo = std::numeric_limits<int64_t>::min(),
                    hi = std::numeric_limits<int64_t>::max();
  return static_cast<int64_t>(std::clamp<Wide>(v, lo, hi));
}

}  // namespace

DeviceClock::Mapped DeviceClock::Rebase(int64_t stamp_ns, int64_t now_ns, Verdict verdict) {
  // The timeline goes on by the time the daemon saw pass (at least 1 ns).
  const int64_t timeline =
      Clamp(Wide{newest_->timeline_ns} + std::max<Wide>(1, Wide{now_ns} - newest_->taken_at_ns));
  const int64_t fell_back = Clamp(Wide{newest_->timeline_ns} - offset_ns_ - stamp_ns);
  offset_ns_ = Clamp(Wide{timeline} - stamp_ns);
  newest_ = Newest{timeline, now_ns};
  refused_future_ns_.reset();
  forgotten_ = false;
  return {verdict, timeline, fell_back};
}

DeviceClock::Mapped DeviceClock::Take(int64_t stamp_ns, int64_t now_ns) {
  if (!newest_) {
    newest_ = Newest{Clamp(Wide{stamp_ns} + offset_ns_), now_ns};
    return {Verdict::kTaken, newest_->timeline_ns, 0};
  }
  if (forgotten_) return Rebase(stamp_ns, now_ns, Verdict::kTaken);
  const Wide ahead = Wide{stamp_ns} + offset_ns_ - newest_->timeline_ns;
  // A headset that went quiet comes back as far ahead as the daemon's clock went on.
  const Wide quiet_ns = std::max<Wide>(0, Wide{now_ns} - newest_->taken_at_ns);
  if (ahead > Wide{options_.max_future_ns} + quiet_ns) {
    const Wide from_refused = refused_future_ns_ ? Wide{stamp_ns} - *refused_future_ns_ : 0;
    if (!refused_future_ns_ || from_refused > options_.max_future_ns ||
        from_refused < -options_.max_future_ns) {
      refused_future_ns_ = stamp_ns;
      return {Verdict::kFuture, 0, 0};
    }
    return Rebase(stamp_ns, now_ns, Verdict::kRestarted);
  }
  if (ahead < -options_.restart_gap_ns) return Rebase(stamp_ns, now_ns, Verdict::kRestarted);
  refused_future_ns_.reset();
  const int64_t timeline = Clamp(Wide{stamp_ns} + offset_ns_);
  if (timeline > newest_->timeline_ns) newest_ = Newest{timeline, now_ns};
  return {Verdict::kTaken, timeline, 0};
}

void DeviceClock::Restore(int64_t newest_timeline_ns, int64_t offset_ns, int64_t now_ns) {
  newest_ = Newest{newest_timeline_ns, now_ns};
  offset_ns_ = offset_ns;
  refused_future_ns_.reset();
  forgotten_ = false;
}

void DeviceClock::Reset() {
  refused_future_ns_.reset();
  forgotten_ = newest_.has_value();
}

}  // namespace floorpose::platform
