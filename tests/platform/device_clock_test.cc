#include "platform/device_clock.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

namespace floorpose::platform {
namespace {

constexpr int64_t kS = 1'000'000'000;
constexpr int64_t kPoison = (int64_t{1} << 62) - 1;
using V = DeviceClock::Verdict;

TEST(DeviceClockTest, StampsInOrderAreTheirOwnTimeline) {
  DeviceClock c({10 * kS, 5 * kS});
  for (int64_t t : {100 * kS, 100 * kS + 3, 101 * kS, 99 * kS /* late, within the gap */}) {
    const auto m = c.Take(t, 0);
    EXPECT_EQ(m.verdict, V::kTaken);
    EXPECT_EQ(m.timeline_ns, t);
  }
  EXPECT_EQ(c.newest_ns(), 101 * kS);
}

TEST(DeviceClockTest, OneStampFromTheFarFutureIsRefusedAndChangesNothing) {
  DeviceClock c({10 * kS, 5 * kS});
  c.Take(100 * kS, 0);
  EXPECT_EQ(c.Take(kPoison, 0).verdict, V::kFuture);
  const auto next = c.Take(100 * kS + kS / 3, 0);
  EXPECT_EQ(next.verdict, V::kTaken);
  EXPECT_EQ(next.timeline_ns, 100 * kS + kS / 3);
  // Refused once more, after a good one: still one bad stamp, not a clock.
  EXPECT_EQ(c.Take(kPoison, 0).verdict, V::kFuture);
  EXPECT_EQ(c.Take(100 * kS + 2 * kS / 3, 0).verdict, V::kTaken);
}

TEST(DeviceClockTest, AClockThatStartsAgainGoesOnFromTheNewestStamp) {
  DeviceClock c({10 * kS, 5 * kS});
  c.Take(1000 * kS, /*now_ns=*/0);
  // The app restarted 2 s later (daemon clock): its stamps begin at 0.
  const auto restart = c.Take(0, 2 * kS);
  EXPECT_EQ(restart.verdict, V::kRestarted);
  EXPECT_EQ(restart.timeline_ns, 1002 * kS);
  EXPECT_EQ(restart.fell_back_ns, 1000 * kS);
  const auto next = c.Take(kS / 2, 0);
  EXPECT_EQ(next.verdict, V::kTaken);
  EXPECT_EQ(next.timeline_ns, 1002 * kS + kS / 2);
}

TEST(DeviceClockTest, OneStampFromThePastCannotLockTheDeviceOut) {
  DeviceClock c({10 * kS, 5 * kS});
  c.Take(1000 * kS, 0);
  // One message stamped at -2^62 looks like a restart...
  EXPECT_EQ(c.Take(-kPoison, kS).verdict, V::kRestarted);
  // ...then the device's own stamps are ahead of it: the first is refused, the second
  // (as far ahead, from the same clock) takes the clock back.
  EXPECT_EQ(c.Take(1000 * kS + kS / 3, kS).verdict, V::kFuture);
  const auto back = c.Take(1000 * kS + 2 * kS / 3, 2 * kS);
  EXPECT_EQ(back.verdict, V::kRestarted);
  EXPECT_GT(back.timeline_ns, 1000 * kS);
  const auto next = c.Take(1001 * kS, 2 * kS);
  EXPECT_EQ(next.verdict, V::kTaken);
  EXPECT_EQ(next.timeline_ns, back.timeline_ns + (kS - 2 * kS / 3));
}

TEST(DeviceClockTest, ExtremeStampsNeverOverflow) {
  DeviceClock c({10 * kS, 5 * kS});
  c.Take(kPoison, 0);  // the first stamp is taken whatever it is
  EXPECT_EQ(c.Take(-kPoison, kS).verdict, V::kRestarted);
  EXPECT_EQ(c.Take(kPoison, kS).verdict, V::kFuture);
  EXPECT_EQ(c.Take(kPoison, kS).verdict, V::kRestarted);
  EXPECT_GE(c.newest_ns(), kPoison);
  // The daemon's clock at its extremes too (a fuzzed replay): the time since the newest
  // stamp is taken wide, and the timeline still goes forward.
  const int64_t newest = c.newest_ns();
  EXPECT_EQ(c.Take(-kPoison, std::numeric_limits<int64_t>::min() + 1).verdict, V::kRestarted);
  EXPECT_GT(c.newest_ns(), newest);
  c.Take(kPoison, std::numeric_limits<int64_t>::max());
  EXPECT_GT(c.newest_ns(), newest);
}

TEST(DeviceClockTest, ResetTakesTheNextStampWhateverItIsAndNeverGoesBack) {
  DeviceClock c({10 * kS, 5 * kS});
  c.Take(1000 * kS, 0);
  c.Reset();
  const auto m = c.Take(5000 * kS, kS);
  EXPECT_EQ(m.verdict, V::kTaken);
  EXPECT_EQ(m.timeline_ns, 1001 * kS);
  EXPECT_EQ(c.Take(5001 * kS, kS).timeline_ns, 1002 * kS);
}

TEST(DeviceClockTest, RestoreCarriesTheOffset) {
  DeviceClock c({10 * kS, 5 * kS});
  c.Restore(/*newest_timeline_ns=*/1002 * kS, /*offset_ns=*/1000 * kS, 0);
  const auto m = c.Take(3 * kS, 0);
  EXPECT_EQ(m.verdict, V::kTaken);
  EXPECT_EQ(m.timeline_ns, 1003 * kS);
}

}  // namespace
}  // namespace floorpose::platform
