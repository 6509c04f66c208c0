#include "platform/pose_history.h"

#include <gtest/gtest.h>

namespace floorpose::platform {
namespace {

v1::PlanPose Published(int64_t stamp_ns, double x) {
  v1::PlanPose p;
  p.set_source_stamp_ns(stamp_ns);
  p.set_x(x);
  p.set_alignment_version(1);
  p.mutable_reliability()->set_flag(v1::Reliability::RELIABLE);
  return p;
}

TEST(PoseHistoryTest, KeepsTheTrackForItsHistoryAndMovesItUnderTheAlignment) {
  PoseHistory history;
  AlignmentState a;
  for (int i = 0; i < 10; ++i) {
    Pose2 slam;
    slam.position = {static_cast<double>(i), 0.0};
    history.Record(slam, Published(i * 500'000'000LL, 100.0 + i), 2.0);
  }
  EXPECT_FALSE(history.Track(a, "0"));  // no alignment: nothing to move the track under
  a.version = 7;
  a.T_plan_slam = Se2{0.0, Eigen::Vector2d(10, 20)};
  const auto track = history.Track(a, "2");
  ASSERT_TRUE(track);
  // 4.5 s is the newest: the poses from 2.5 s on are within 2 s of it.
  ASSERT_EQ(track->poses_size(), 5);
  EXPECT_EQ(track->floor(), "2");
  EXPECT_EQ(track->alignment_version(), 7u);
  for (int i = 0; i < track->poses_size(); ++i) {
    const v1::PlanPose& p = track->poses(i);
    EXPECT_EQ(p.source_stamp_ns(), (5 + i) * 500'000'000LL);
    EXPECT_DOUBLE_EQ(p.x(), 15.0 + i);  // moved: slam x under the alignment, not as published
    EXPECT_DOUBLE_EQ(p.y(), 20.0);
    EXPECT_EQ(p.alignment_version(), 7u);
    EXPECT_EQ(p.reliability().flag(), v1::Reliability::RELIABLE);  // as it was published
  }
  history.ClearTrack();
  EXPECT_FALSE(history.Track(a, "2"));
}

TEST(PoseHistoryTest, KeepsNoTrackAtZeroHistoryButTheLatestPose) {
  PoseHistory history;
  history.Record(Pose2{}, Published(1, 1.0), 0.0);
  AlignmentState a;
  a.version = 1;
  EXPECT_FALSE(history.Track(a, "0"));
  EXPECT_FALSE(history.latest());
  EXPECT_FALSE(history.eye_z());
  history.SetLatest(Published(1, 1.0));
  history.SetEyeZ(1.6);
  ASSERT_TRUE(history.latest());
  EXPECT_EQ(history.latest()->x(), 1.0);
  EXPECT_EQ(*history.eye_z(), 1.6);
  history.ForgetLatest();
  EXPECT_FALSE(history.latest());
  EXPECT_TRUE(history.eye_z());  // the headset's height stays: it is not of the plan
}

}  // namespace
}  // namespace floorpose::platform
