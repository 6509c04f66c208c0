// One headset's stamps made into a timeline that only goes forward. A stamp far ahead of
// the newest one taken (further than the daemon's clock went on since) is refused (one bad stamp
// must not make every later message look old); a clock that falls back by more than a gap has
// started again (the app restarted) and the timeline carries on from where it was, so the wall
// store, the tracker's timers and the path keep their order. The engine works on the timeline and
// publishes the device's own stamps.
#pragma once

#include <cstdint>
#include <optional>

namespace floorpose::platform {

class DeviceClock {
 public:
  struct Options {
    int64_t max_future_ns = 10'000'000'000;  // limits.max_future_s
    int64_t restart_gap_ns = 5'000'000'000;  // limits.restart_gap_s
  };
  enum class Verdict {
    kTaken,      // on the timeline (maybe behind its newest stamp: a late message)
    kFuture,     // refused: too far ahead of the newest stamp taken
    kRestarted,  // the device's clock started again: taken, right after the newest stamp
  };
  struct Mapped {
    Verdict verdict = Verdict::kTaken;
    int64_t timeline_ns = 0;   // when taken
    int64_t fell_back_ns = 0;  // kRestarted: how far the stamp was behind (< 0: ahead)
  };

  explicit DeviceClock(Options options) : options_(options) {}

  // Maps a device stamp; now_ns is the daemon's clock, which tells how long a restart took
  // and how far ahead a headset that went quiet may come back. A stamp further ahead of
  // the newest taken than max_future plus the daemon time since is refused, unless the one refused
  // just before it was too, and this one is within max_future of it: two in a row from one clock
  // mean that clock is the device's (and one bad stamp from the past cannot lock the device out).
  Mapped Take(int64_t stamp_ns, int64_t now_ns);

  // The newest timeline stamp taken (0 before any).
  int64_t newest_ns() const { return newest_ ? newest_->timeline_ns : 0; }
  // Timeline minus device stamp.
  int64_t offset_ns() const { return offset_ns_; }
  // After a restart of the daemon: the timeline as saved (newest stamp and offset).
  void Restore(int64_t newest_timeline_ns, int64_t offset_ns, int64_t now_ns);
  // Forgets the device's clock (Command.reset): the next stamp is taken whatever it is,
  // right after the newest one on the timeline, which never goes back.
  void Reset();

 private:
  struct Newest {
    int64_t timeline_ns = 0;
    int64_t taken_at_ns = 0;  // the daemon's clock when it was taken
  };
  // Starts the device's clock again at stamp_ns.
  Mapped Rebase(int64_t stamp_ns, int64_t now_ns, Verdict verdict);

  Options options_;
  std::optional<Newest> newest_;
  int64_t offset_ns_ = 0;
  bool forgotten_ = false;                    // Reset since the last stamp taken
  std::optional<int64_t> refused_future_ns_;  // the last message's stamp, if it was refused
};

}  // namespace floorpose::platform
