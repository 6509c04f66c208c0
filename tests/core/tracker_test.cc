// The tracker: the wall pick of eq. 6.2, the flip, the state machine and the acceptance
// rule of section 6.4.3, driven with injected stamps (no clock, no sleeps).
#include "core/tracker.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

#include "core/random.h"
#include "tests/test_util.h"

namespace floorpose {
namespace {

using testing::Deg;
using ::testing::HasSubstr;
using testing::IsNearlySe2;
using ::testing::Not;

// The pick a wearer makes when slam and plan are related by T_plan_slam: a point on a
// plan wall with its normal, and the same point and normal seen in slam.
WallPick PickFor(const Se2& T_plan_slam, const Eigen::Vector2d& plan_point,
                 const Eigen::Vector2d& plan_normal) {
  const Se2 T_slam_plan = T_plan_slam.Inverse();
  return {T_slam_plan * plan_point, T_slam_plan.R() * plan_normal, plan_point, plan_normal};
}

TEST(AlignFromWallPickTest, RecoversRandomTransformsExactly) {
  // Equation 6.2: one point with its normal fixes all three degrees of freedom.
  const FloorPlan plan = testing::AsymmetricRoom();
  SplitMix64 rng(51);
  for (int i = 0; i < 500; ++i) {
    const Se2 truth{rng.Uniform(-M_PI, M_PI), {rng.Uniform(-50, 50), rng.Uniform(-50, 50)}};
    const Segment& wall = plan.segments[rng.Next() % plan.segments.size()];
    const Eigen::Vector2d point = wall.a + rng.Uniform() * (wall.b - wall.a);
    WallPick pick = PickFor(truth, point, wall.Normal());
    pick.slam_normal *= rng.Uniform(0.5, 2.0);  // the normals need not be unit
    const auto T = AlignFromWallPick(pick);
    ASSERT_TRUE(T.has_value());
    EXPECT_THAT(*T, IsNearlySe2(truth, 1e-9, 1e-12));
  }
}

TEST(AlignFromWallPickTest, RejectsZeroAndNonFiniteInput) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const WallPick good = PickFor(Se2{0.3, {1, 2}}, {4, 2}, {1, 0});
  ASSERT_TRUE(AlignFromWallPick(good).has_value());
  WallPick bad = good;
  bad.slam_normal = {0, 0};
  EXPECT_FALSE(AlignFromWallPick(bad).has_value());
  bad = good;
  bad.plan_normal = {1e-9, 0};
  EXPECT_FALSE(AlignFromWallPick(bad).has_value());
  bad = good;
  bad.slam_point.x() = nan;
  EXPECT_FALSE(AlignFromWallPick(bad).has_value());
  bad = good;
  bad.plan_normal.y() = nan;
  EXPECT_FALSE(AlignFromWallPick(bad).has_value());
}

class TrackerTest : public ::testing::Test {
 protected:
  TrackerTest()
      : plan_(testing::AsymmetricRoom()),
        index_(std::make_shared<const ClosestWallIndex>(plan_)),
        tracker_(TrackerOptions{}) {}

  // Wall points every 2 cm, in the slam frame of truth_.
  std::vector<Eigen::Vector2d> Cloud() const {
    std::vector<Eigen::Vector2d> out;
    const Se2 T_slam_plan = truth_.Inverse();
    for (const auto& p : testing::SampleWalls(plan_, 0.02)) out.push_back(T_slam_plan * p);
    return out;
  }

  // The wearer's walk in the slam frame of truth_: 0.25 m steps along y = 2 of the plan,
  // from x = from_x to to_x (the inner wall is x = 4).
  std::vector<Eigen::Vector2d> WalkAlongY2(double from_x, double to_x) const {
    std::vector<Eigen::Vector2d> path;
    for (double x = from_x; x <= to_x + 1e-9; x += 0.25)
      path.push_back(truth_.Inverse() * Eigen::Vector2d(x, 2));
    return path;
  }

  // A registration result for transform T on the cloud, as RegisterIcp would report it.
  RegistrationResult ResultFor(const Se2& T, const std::vector<Eigen::Vector2d>& cloud) const {
    RegistrationResult r;
    r.method = "test";
    r.T_plan_slam = T;
    r.converged = true;
    EvaluateFit(cloud, *index_, T, 1.5, 0.2, &r, nullptr);
    return r;
  }

  // A pick, then several agreeing results (a tight filter), then the wearer at (2, 2).
  void Settle(Tracker& tracker) const {
    tracker.SetPlan(index_);
    ASSERT_EQ(tracker.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
    const auto cloud = Cloud();
    for (int i = 0; i < 5; ++i) {
      const Tracker::Decision d =
          tracker.Offer(ResultFor(truth_, cloud), cloud, tracker.alignment().version, 2 + i);
      ASSERT_TRUE(d.accepted) << d.reason;
    }
    tracker.Correct({truth_.Inverse() * Eigen::Vector2d(2, 2), 0, 1.6});
  }

  // The wall points in the slam frame after the odometry slipped: 15 degrees about the
  // wearer and 0.6 m.
  Se2 Slipped() const { return truth_ * Se2{Deg(15), {0.6, -0.3}}; }
  std::vector<Eigen::Vector2d> SlippedCloud() const {
    std::vector<Eigen::Vector2d> cloud;
    for (const auto& p : testing::SampleWalls(plan_, 0.02))
      cloud.push_back(Slipped().Inverse() * p);
    return cloud;
  }

  FloorPlan plan_;
  std::shared_ptr<const ClosestWallIndex> index_;
  Tracker tracker_;
  const Se2 truth_{Deg(20), {3.0, -1.5}};  // T_plan_slam
};

TEST_F(TrackerTest, StatesFromPlanToPick) {
  EXPECT_EQ(tracker_.state(), TrackState::kWaitingForPlan);
  EXPECT_STREQ(ToString(tracker_.state()), "WAITING_FOR_PLAN");
  EXPECT_THAT(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), HasSubstr("plan"));

  tracker_.SetPlan(index_);
  EXPECT_TRUE(tracker_.has_plan());
  EXPECT_EQ(tracker_.state(), TrackState::kWaitingForAlignment);
  EXPECT_FALSE(tracker_.has_alignment());
  EXPECT_EQ(tracker_.CurrentReliability().flag, ReliabilityFlag::kUnreliable);

  WallPick zero = PickFor(truth_, {4, 2}, {1, 0});
  zero.slam_normal = {0, 0};
  EXPECT_FALSE(tracker_.ApplyWallPick(zero, 1).empty());
  EXPECT_EQ(tracker_.state(), TrackState::kWaitingForAlignment);

  EXPECT_EQ(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 5), "");
  // A pick alone is not checked against the walls yet: DEGRADED until a registration.
  EXPECT_EQ(tracker_.state(), TrackState::kDegraded);
  EXPECT_STREQ(ToString(tracker_.state()), "DEGRADED");
  EXPECT_EQ(tracker_.alignment().version, 1u);
  EXPECT_EQ(tracker_.alignment().source, AlignmentSource::kWallPick);
  EXPECT_EQ(tracker_.alignment().stamp_ns, 5);
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(truth_, 1e-9, 1e-12));

  // A new plan drops the alignment, which belonged to the old one.
  tracker_.SetPlan(index_);
  EXPECT_EQ(tracker_.state(), TrackState::kWaitingForAlignment);
  EXPECT_EQ(tracker_.alignment().version, 0u);
}

TEST_F(TrackerTest, FlipTurnsHalfAroundThePickPoint) {
  tracker_.SetPlan(index_);
  EXPECT_FALSE(tracker_.Flip(1).empty());  // nothing to flip yet
  const WallPick pick = PickFor(truth_, {4, 2}, {1, 0});
  ASSERT_EQ(tracker_.ApplyWallPick(pick, 1), "");
  const Se2 before = tracker_.alignment().T_plan_slam;
  ASSERT_EQ(tracker_.Flip(2), "");
  const Se2 after = tracker_.alignment().T_plan_slam;

  EXPECT_EQ(tracker_.alignment().source, AlignmentSource::kFlip);
  EXPECT_EQ(tracker_.alignment().version, 2u);
  // The pick point maps to itself; the heading turns by pi; everything else mirrors
  // through the pick point.
  EXPECT_NEAR((after * pick.slam_point - pick.plan_point).norm(), 0.0, 1e-9);
  EXPECT_NEAR(std::abs(WrapAngle(after.theta - before.theta)), M_PI, 1e-12);
  SplitMix64 rng(52);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector2d p = testing::RandomVector2(rng, {-20, -20}, {20, 20});
    EXPECT_NEAR((after * p - (2 * pick.plan_point - before * p)).norm(), 0.0, 1e-9);
  }
  EXPECT_EQ(tracker_.state(), TrackState::kDegraded);
  // Flipping twice is the identity.
  ASSERT_EQ(tracker_.Flip(3), "");
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(before, 1e-9, 1e-12));
}

TEST_F(TrackerTest, CorrectAppliesTheAlignment) {
  tracker_.SetPlan(index_);
  // Before any alignment the pose passes through, flagged unreliable.
  const Pose2 pose{{1.5, -2.0}, 0.4, 1.7};
  PlanPoseEstimate e = tracker_.Correct(pose);
  EXPECT_EQ(e.alignment_version, 0u);
  EXPECT_EQ(e.reliability.flag, ReliabilityFlag::kUnreliable);
  EXPECT_EQ(e.pose.position, pose.position);

  // Random poses jump through walls and out of the plan: those checks are other tests'.
  TrackerOptions options;
  options.path_check = false;
  options.off_plan_margin_m = 0;
  tracker_ = Tracker(options);
  tracker_.SetPlan(index_);
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
  SplitMix64 rng(53);
  for (int i = 0; i < 50; ++i) {
    const Pose2 p{testing::RandomVector2(rng, {-10, -10}, {10, 10}), rng.Uniform(-M_PI, M_PI),
                  rng.Uniform(0, 2)};
    e = tracker_.Correct(p);
    EXPECT_NEAR((e.pose.position - (truth_.R() * p.position + truth_.t)).norm(), 0.0, 1e-9);
    EXPECT_NEAR(WrapAngle(e.pose.heading - (p.heading + truth_.theta)), 0.0, 1e-12);
    EXPECT_EQ(e.pose.z, p.z);
    EXPECT_EQ(e.alignment_version, 1u);
    EXPECT_EQ(e.reliability.flag, ReliabilityFlag::kDegraded);
  }
}

// A wrong pick's few walls often fit some corner near it as well as they fit the truth;
// the walk so far tells such a first place apart: the wearer walked through no wall.
TEST_F(TrackerTest, AFirstPlaceThatWalksTheWearerThroughAWallIsNotTaken) {
  const auto cloud = Cloud();
  const std::vector<Eigen::Vector2d> through = WalkAlongY2(2.1, 6.1);  // across the inner wall
  const std::vector<Eigen::Vector2d> clear = WalkAlongY2(5, 9);
  const Se2 picked = Se2{Deg(2), {0.1, -0.1}} * truth_;

  tracker_.SetPlan(index_);
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(picked, {4, 2}, {1, 0}), 1), "");
  const uint64_t v1 = tracker_.alignment().version;
  Tracker::Decision d = tracker_.Offer(ResultFor(truth_, cloud), cloud, v1, 2, through);
  EXPECT_FALSE(d.accepted);
  EXPECT_EQ(d.reason, "first place: the walk so far would cross 1 wall of the plan there");
  EXPECT_EQ(tracker_.alignment().version, v1);
  EXPECT_EQ(tracker_.alignment().source, AlignmentSource::kWallPick);
  // The pick it refined is in doubt too: flagged until an alignment walks the wearer clear.
  EXPECT_TRUE(tracker_.path_crossed());
  EXPECT_EQ(tracker_.CurrentReliability().flag, ReliabilityFlag::kUnreliable);
  EXPECT_THAT(tracker_.CurrentReliability().reason, HasSubstr("crosses a wall"));

  // The same place with a walk that stays in the room is taken at once (clear, within
  // the pick search); from then on the path check of every pose is the tracker's.
  d = tracker_.Offer(ResultFor(truth_, cloud), cloud, v1, 3, clear);
  ASSERT_TRUE(d.accepted) << d.reason;
  EXPECT_EQ(tracker_.alignment().source, AlignmentSource::kRegistration);
  EXPECT_FALSE(tracker_.path_crossed());
  d = tracker_.Offer(ResultFor(truth_, cloud), cloud, tracker_.alignment().version, 4, through);
  EXPECT_TRUE(d.accepted) << d.reason;

  // With path_check off, nothing is checked.
  TrackerOptions options;
  options.path_check = false;
  Tracker unchecked(options);
  unchecked.SetPlan(index_);
  ASSERT_EQ(unchecked.ApplyWallPick(PickFor(picked, {4, 2}, {1, 0}), 1), "");
  d = unchecked.Offer(ResultFor(truth_, cloud), cloud, unchecked.alignment().version, 2, through);
  EXPECT_TRUE(d.accepted) << d.reason;
}

TEST_F(TrackerTest, OfferAcceptsBetterRejectsWorseAndStale) {
  tracker_.SetPlan(index_);
  // The pick is 2 degrees and 15 cm off the truth.
  const Se2 picked = Se2{Deg(2), {0.1, -0.1}} * truth_;
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(picked, {4, 2}, {1, 0}), 1), "");
  const uint64_t v1 = tracker_.alignment().version;
  const auto cloud = Cloud();

  // Worse than the alignment in use: rejected, nothing changes.
  const Se2 worse = Se2{Deg(5), {0.3, 0.2}} * truth_;
  Tracker::Decision d = tracker_.Offer(ResultFor(worse, cloud), cloud, v1, 2);
  EXPECT_FALSE(d.accepted);
  EXPECT_THAT(d.reason, HasSubstr("worse"));
  EXPECT_EQ(tracker_.alignment().version, v1);
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(picked, 1e-9, 1e-12));

  // Based on an alignment that is no longer in use: rejected even though it is better.
  d = tracker_.Offer(ResultFor(truth_, cloud), cloud, v1 + 1, 3);
  EXPECT_FALSE(d.accepted);
  EXPECT_THAT(d.reason, HasSubstr("alignment changed"));
  EXPECT_EQ(tracker_.alignment().version, v1);

  // A failed registration is never taken.
  RegistrationResult failed = ResultFor(truth_, cloud);
  failed.matched = 0;
  failed.reason = "fewer than 3 correspondences";
  EXPECT_FALSE(tracker_.Offer(failed, cloud, v1, 4).accepted);
  RegistrationResult nan = ResultFor(truth_, cloud);
  nan.T_plan_slam.theta = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(tracker_.Offer(nan, cloud, v1, 4).accepted);

  // A first place after a pick that another place nearly matches (but not within
  // max_ambiguity) waits for the next result to land on it too.
  RegistrationResult first = ResultFor(truth_, cloud);
  first.ambiguity = 0.5;
  d = tracker_.Offer(first, cloud, v1, 5);
  EXPECT_FALSE(d.accepted);
  EXPECT_THAT(d.reason, HasSubstr("first place"));
  EXPECT_EQ(tracker_.alignment().version, v1);

  // Better and current: fused, a new version, and the fit makes it reliable. The pick
  // is 1.5 m and 5 degrees uncertain, the registration a few centimetres: the result
  // is taken almost whole.
  d = tracker_.Offer(first, cloud, v1, 5);
  EXPECT_TRUE(d.accepted) << d.reason;
  EXPECT_GT(tracker_.alignment().version, v1);
  EXPECT_EQ(tracker_.alignment().source, AlignmentSource::kRegistration);
  EXPECT_EQ(tracker_.alignment().stamp_ns, 5);
  ASSERT_TRUE(tracker_.alignment().registration.has_value());
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(truth_, 0.01, 0.001));
  ASSERT_EQ(tracker_.history().size(), 1u);
  EXPECT_EQ(tracker_.history().back().version, tracker_.alignment().version);
  EXPECT_EQ(tracker_.state(), TrackState::kTracking);
  const Reliability r = tracker_.CurrentReliability();
  EXPECT_EQ(r.flag, ReliabilityFlag::kReliable);
  EXPECT_GT(r.probability, 0.9);

  // The same offer again, on the old version, is stale.
  d = tracker_.Offer(ResultFor(truth_, cloud), cloud, v1, 6);
  EXPECT_FALSE(d.accepted);
  EXPECT_THAT(d.reason, HasSubstr("alignment changed"));
}

// The odometry slips in a turn (CARMEN csail): the alignment in use is suddenly degrees
// off, and the correct results after it lie beyond the filter's gate. One that explains
// the walls the alignment in use no longer explains is taken at once; one that explains
// them only a little better still waits for confirmation.
TEST_F(TrackerTest, ResultThatExplainsTheWallsInsteadIsTakenAtOnce) {
  TrackerOptions on;
  on.jump_clear_ratio = 0.6;  // as tracking.wheel_odometry sets it
  tracker_ = Tracker(on);
  Settle(tracker_);
  ASSERT_FALSE(HasFatalFailure());
  const Se2 slipped = Slipped();
  const std::vector<Eigen::Vector2d> cloud = SlippedCloud();
  const uint64_t v = tracker_.alignment().version;

  // A result a little better than the alignment in use, with few walls on the plan: waits.
  const Se2 partway = truth_ * Se2{Deg(8), {0.3, -0.15}};
  Tracker::Decision d = tracker_.Offer(ResultFor(partway, cloud), cloud, v, 10);
  EXPECT_FALSE(d.accepted);
  EXPECT_THAT(d.reason, HasSubstr("waits for confirmation"));
  EXPECT_EQ(tracker_.alignment().version, v);

  // The right place: every wall on the plan, where the alignment in use has few.
  d = tracker_.Offer(ResultFor(slipped, cloud), cloud, v, 11);
  EXPECT_TRUE(d.accepted) << d.reason;
  EXPECT_THAT(d.reason, HasSubstr("the walls fit it, not the alignment in use"));
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(slipped, 1e-6, 1e-6));

  // Off (jump_clear_ratio 0, a headset's default), the same offer waits.
  Tracker off(TrackerOptions{});
  Settle(off);
  ASSERT_FALSE(HasFatalFailure());
  d = off.Offer(ResultFor(slipped, cloud), cloud, off.alignment().version, 11);
  EXPECT_FALSE(d.accepted);
  EXPECT_THAT(d.reason, HasSubstr("waits for confirmation"));
}

// After the same slip, with the jump not taken at once (a headset): the filter is sure of
// a place the walls no longer fit, so the next registration searches around it as after
// a pick, instead of running ICP into the nearest minimum from there.
TEST_F(TrackerTest, AlignmentTheWallsStoppedFittingIsSearchedAround) {
  Settle(tracker_);
  ASSERT_FALSE(HasFatalFailure());
  const TrackerOptions& o = tracker_.options();
  EXPECT_EQ(tracker_.NextRegistrationOptions().search_window_m, 0);  // a tight filter

  // A wrong result while the walls fit the alignment in use: no search.
  const auto cloud = Cloud();
  const Se2 wrong = truth_ * Se2{Deg(5), {0.8, 0.4}};
  Tracker::Decision d =
      tracker_.Offer(ResultFor(wrong, cloud), cloud, tracker_.alignment().version, 10);
  ASSERT_FALSE(d.accepted);
  EXPECT_EQ(tracker_.NextRegistrationOptions().search_window_m, 0);

  // The slip: the right result disagrees, and the alignment in use fits few walls.
  const auto slipped = SlippedCloud();
  d = tracker_.Offer(ResultFor(Slipped(), slipped), slipped, tracker_.alignment().version, 11);
  ASSERT_FALSE(d.accepted);
  EXPECT_THAT(d.reason, HasSubstr("waits for confirmation"));
  const RegistrationOptions next = tracker_.NextRegistrationOptions();
  EXPECT_EQ(next.search_window_m, o.pick_search_m);
  EXPECT_EQ(next.search_window_rad, o.pick_search_rad);
  ASSERT_TRUE(next.search_pivot.has_value());

  // Off: ICP from the alignment in use, as before.
  TrackerOptions no_search;
  no_search.search_unexplained = false;
  Tracker off(no_search);
  Settle(off);
  ASSERT_FALSE(HasFatalFailure());
  d = off.Offer(ResultFor(Slipped(), slipped), slipped, off.alignment().version, 11);
  ASSERT_FALSE(d.accepted);
  EXPECT_EQ(off.NextRegistrationOptions().search_window_m, 0);
}

TEST_F(TrackerTest, AmbiguousResultAfterAPickIsRefused) {
  tracker_.SetPlan(index_);
  const Se2 picked = Se2{Deg(2), {0.3, -0.2}} * truth_;
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(picked, {4, 2}, {1, 0}), 1), "");
  const uint64_t v1 = tracker_.alignment().version;
  const auto cloud = Cloud();
  // Another place scored within 5% of this one: the pick stays until the walls decide.
  RegistrationResult r = ResultFor(truth_, cloud);
  r.ambiguity = 0.95;
  const Tracker::Decision d = tracker_.Offer(r, cloud, v1, 2);
  EXPECT_FALSE(d.accepted);
  EXPECT_THAT(d.reason, HasSubstr("ambiguous"));
  EXPECT_EQ(tracker_.alignment().version, v1);
  // The next one stands out: taken.
  r.ambiguity = 0.2;
  EXPECT_TRUE(tracker_.Offer(r, cloud, v1, 3).accepted);
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(truth_, 0.01, 0.001));
}

TEST_F(TrackerTest, AmbiguousPlaceIsTakenOnceLaterResultsKeepLandingOnIt) {
  tracker_.SetPlan(index_);
  const Se2 picked = Se2{Deg(2), {0.3, -0.2}} * truth_;
  const Se2 T_slam_plan = picked.Inverse();
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(picked, {4, 2}, {1, 0}), 1), "");
  const auto cloud = Cloud();
  RegistrationResult r = ResultFor(truth_, cloud);
  r.ambiguity = 0.95;
  // The wearer walks 1 m between registrations that all land on the same place.
  int64_t t = 2;
  for (int metre = 0; metre < 10; ++metre, ++t) {
    tracker_.Correct({T_slam_plan * Eigen::Vector2d(-3.0 + metre, 3.0), 0.0, 0.0});
    const Tracker::Decision d = tracker_.Offer(r, cloud, tracker_.alignment().version, t);
    EXPECT_FALSE(d.accepted) << metre;
    EXPECT_THAT(d.reason, HasSubstr("ambiguous"));
  }
  tracker_.Correct({T_slam_plan * Eigen::Vector2d(7.0, 3.0), 0.0, 0.0});
  EXPECT_TRUE(tracker_.Offer(r, cloud, tracker_.alignment().version, t).accepted);
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(truth_, 0.01, 0.001));
}

TEST_F(TrackerTest, ClearFirstPlaceIsTakenAtOnceUnlessFarFromThePick) {
  tracker_.SetPlan(index_);
  const auto cloud = Cloud();
  RegistrationResult r = ResultFor(truth_, cloud);
  r.ambiguity = 0.1;
  // The pick 1.5 m and 6 degrees off: within the pick search, so a clear result that
  // fits is taken at once, the wearer's pose corrected from the next one on.
  const Se2 picked = Se2{Deg(6), {1.2, -0.9}} * truth_;
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(picked, {4, 2}, {1, 0}), 1), "");
  tracker_.Correct({truth_.Inverse() * Eigen::Vector2d(3, 3), 0.0, 0.0});
  Tracker::Decision d = tracker_.Offer(r, cloud, tracker_.alignment().version, 2);
  EXPECT_TRUE(d.accepted) << d.reason;
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(truth_, 0.05, 0.005));

  // The pick 4 m off: further than a pick can be, so the same result waits for the
  // next one to agree.
  const Se2 far = Se2{0.0, {4.0, 0.0}} * truth_;
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(far, {4, 2}, {1, 0}), 3), "");
  tracker_.Correct({truth_.Inverse() * Eigen::Vector2d(3, 3), 0.0, 0.0});
  d = tracker_.Offer(r, cloud, tracker_.alignment().version, 4);
  EXPECT_FALSE(d.accepted);
  EXPECT_THAT(d.reason, HasSubstr("first place"));
  EXPECT_TRUE(tracker_.Offer(r, cloud, tracker_.alignment().version, 5).accepted);
}

TEST_F(TrackerTest, FirstRegistrationNeedsMostWallPointsToFit) {
  tracker_.SetPlan(index_);
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
  const auto cloud = Cloud();
  RegistrationResult r = ResultFor(truth_, cloud);
  r.inliers = r.points / 2;  // as a place that explains half the walls would report
  const Tracker::Decision d = tracker_.Offer(r, cloud, tracker_.alignment().version, 2);
  EXPECT_FALSE(d.accepted);
  EXPECT_THAT(d.reason, HasSubstr("too few wall points fit"));
  r.inliers = r.points;
  EXPECT_TRUE(tracker_.Offer(r, cloud, tracker_.alignment().version, 3).accepted);
}

TEST_F(TrackerTest, OfferBasedOnAReplacedAlignmentIsStale) {
  // A registration started from the pick; meanwhile the wearer flipped. The result is
  // far better than the flipped alignment, but it answers a question nobody asks any
  // more, so it is dropped.
  tracker_.SetPlan(index_);
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
  const uint64_t started_from = tracker_.alignment().version;
  ASSERT_EQ(tracker_.Flip(2), "");
  const auto cloud = Cloud();
  const Tracker::Decision d = tracker_.Offer(ResultFor(truth_, cloud), cloud, started_from, 3);
  EXPECT_FALSE(d.accepted);
  EXPECT_THAT(d.reason, HasSubstr("alignment changed"));
  EXPECT_EQ(tracker_.alignment().source, AlignmentSource::kFlip);
}

TEST_F(TrackerTest, PickThenIcpThenCorrectEndToEnd) {
  // The daemon's loop in miniature: pick with an error, register from the alignment in
  // use, offer the result, correct poses with it.
  tracker_.SetPlan(index_);
  const Se2 picked = Se2{Deg(-3), {-0.2, 0.25}} * truth_;
  const Se2 T_slam_plan = picked.Inverse();
  ASSERT_EQ(tracker_.ApplyWallPick({T_slam_plan * Eigen::Vector2d(10, 3),
                                    T_slam_plan.R() * Eigen::Vector2d(-1, 0),
                                    {10, 3},
                                    {-1, 0}},
                                   1),
            "");
  const auto cloud = Cloud();
  ASSERT_TRUE(tracker_.RegistrationDue(2'000'000'000, cloud.size(), cloud.size()));
  tracker_.MarkRegistrationStarted(2'000'000'000);
  const uint64_t version = tracker_.alignment().version;
  const RegistrationResult r = RegisterIcp(
      cloud, *tracker_.index(), tracker_.alignment().T_plan_slam, tracker_.options().icp);
  ASSERT_EQ(r.ambiguity, 0.0);  // no search: nothing else competes, taken at once
  ASSERT_TRUE(tracker_.Offer(r, cloud, version, 3).accepted);
  EXPECT_EQ(tracker_.state(), TrackState::kTracking);
  const Pose2 pose{truth_.Inverse() * Eigen::Vector2d(5, 5), 0.0, 1.6};
  EXPECT_NEAR((tracker_.Correct(pose).pose.position - Eigen::Vector2d(5, 5)).norm(), 0.0, 0.02);
}

// After a pick the search covers the pick's error. Once registered on one wall only, the
// direction along it is as uncertain as the pick left it: the next run searches along it
// (with the filter's covariance). Once the whole room is fitted, no search.
TEST_F(TrackerTest, LaterRunsSearchAsFarAsTheAlignmentIsUncertain) {
  tracker_.SetPlan(index_);
  // The pick is 1 m off along the bottom wall and 10 cm across it.
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(Se2{0.0, {1.0, 0.1}} * truth_, {2, 0}, {0, 1}), 1), "");
  const Pose2 wearer{truth_.Inverse() * Eigen::Vector2d(2, 1.5), 0, 1.6};
  tracker_.Correct(wearer);
  const TrackerOptions& o = tracker_.options();
  EXPECT_DOUBLE_EQ(tracker_.NextRegistrationOptions().search_window_m, o.pick_search_m);
  std::vector<Eigen::Vector2d> bottom;  // the bottom wall, x 0 to 4 (the inner wall's foot)
  for (double x = 0.0; x <= 3.9; x += 0.02)
    bottom.push_back(truth_.Inverse() * Eigen::Vector2d(x, 0));
  RegistrationResult along = ResultFor(truth_, bottom);
  const Tracker::Decision d = tracker_.Offer(along, bottom, tracker_.alignment().version, 2);
  ASSERT_TRUE(d.accepted) << d.reason;
  tracker_.Correct(wearer);
  const RegistrationOptions next = tracker_.NextRegistrationOptions();
  ASSERT_TRUE(next.search_covariance.has_value());
  EXPECT_DOUBLE_EQ(next.search_window_m, o.pick_search_m);  // 3 sigma of 1.5 m, capped
  EXPECT_EQ(next.search_tie_ratio, o.search_tie_ratio);
  const Eigen::Matrix3d& P = *next.search_covariance;
  const Eigen::Vector2d along_wall = P.block<2, 2>(1, 1) * Eigen::Vector2d(1, 0);
  EXPECT_GT(along_wall.x(), 1.0);                                   // along the wall: the pick's
  EXPECT_LT(std::sqrt(P(2, 2)), o.search_min_m / o.search_sigmas);  // across: pinned
  const auto room = Cloud();
  ASSERT_TRUE(
      tracker_.Offer(ResultFor(truth_, room), room, tracker_.alignment().version, 3).accepted);
  tracker_.Correct(wearer);
  EXPECT_EQ(tracker_.NextRegistrationOptions().search_window_m, 0.0);
  EXPECT_FALSE(tracker_.NextRegistrationOptions().search_covariance.has_value());
}

// Before a first place is taken, the walls' directions turn the pick about its point: the
// pick's point stays where it was picked, the heading moves (most of the way: the pick's
// 5 degrees against the walls' 1), the heading sigma narrows, and the version changes.
// Not on a stale version, not beyond 3 sigma, not once a registration is in use.
TEST_F(TrackerTest, TurnToWallsTurnsThePickAboutItsPoint) {
  tracker_.SetPlan(index_);
  const Eigen::Vector2d point(4, 2), normal(1, 0);
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(Se2{Deg(4), {0, 0}} * truth_, point, normal), 1), "");
  const Pose2 wearer{truth_.Inverse() * Eigen::Vector2d(2, 1.5), 0, 1.6};
  tracker_.Correct(wearer);
  const Se2 before = tracker_.alignment().T_plan_slam;
  const uint64_t v = tracker_.alignment().version;
  EXPECT_FALSE(tracker_.TurnToWalls(Deg(-4), v + 1, 2));  // stale
  EXPECT_FALSE(tracker_.TurnToWalls(Deg(-20), v, 2));     // beyond 3 sigma of the pick's
  const std::optional<double> turned = tracker_.TurnToWalls(Deg(-4), v, 2);
  ASSERT_TRUE(turned.has_value());
  const Se2& after = tracker_.alignment().T_plan_slam;
  EXPECT_GT(tracker_.alignment().version, v);
  EXPECT_EQ(tracker_.alignment().source, AlignmentSource::kWallPick);
  const Eigen::Vector2d slam_point = before.Inverse() * point;
  EXPECT_NEAR((after * slam_point - point).norm(), 0.0, 1e-9);  // the pick's point stays
  const double s2 = std::pow(tracker_.options().pick_sigma_rad, 2);
  const double m2 = std::pow(tracker_.options().turn_sigma_rad, 2);
  EXPECT_NEAR(*turned, Deg(-4) * s2 / (s2 + m2), 1e-9);
  EXPECT_NEAR(WrapAngle(after.theta - before.theta), *turned, 1e-9);
  EXPECT_LT(tracker_.CurrentFeatures().heading_sigma_deg, 1.5);
  // Once registered, the filter has the heading: no more turns.
  const auto room = Cloud();
  ASSERT_TRUE(
      tracker_.Offer(ResultFor(truth_, room), room, tracker_.alignment().version, 3).accepted);
  EXPECT_FALSE(tracker_.TurnToWalls(Deg(1), tracker_.alignment().version, 4));
}

TEST_F(TrackerTest, CirclingWithoutWallsWidensTheHeadingButScanningDoesNot) {
  tracker_.SetPlan(index_);
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
  const auto room = Cloud();
  ASSERT_TRUE(
      tracker_.Offer(ResultFor(truth_, room), room, tracker_.alignment().version, 2).accepted);
  const Eigen::Vector2d spot = truth_.Inverse() * Eigen::Vector2d(2, 1.5);
  const double fused_deg = tracker_.CurrentFeatures().heading_sigma_deg;
  // Looking left and right for a while: the heading stays as sure as the registration left it.
  for (int i = 0; i < 200; ++i) tracker_.Correct({spot, (i % 2 ? 1 : -1) * Deg(50), 1.6});
  const double scanned_deg = tracker_.CurrentFeatures().heading_sigma_deg;
  EXPECT_LT(scanned_deg, fused_deg + 0.6);
  // Five laps on the spot, one way: the SLAM's own turning error, 5 x 360 x yaw_scale_sigma.
  for (int i = 0; i <= 5 * 36; ++i) tracker_.Correct({spot, WrapAngle(Deg(10) * i), 1.6});
  const double laps_deg = 5 * 360 * tracker_.options().filter.yaw_scale_sigma;
  ASSERT_GT(laps_deg, 5.0);
  EXPECT_NEAR(tracker_.CurrentFeatures().heading_sigma_deg,
              std::sqrt(scanned_deg * scanned_deg + laps_deg * laps_deg), 1.0);
}

TEST_F(TrackerTest, RegistrationDueFollowsPointsAndInjectedTime) {
  const TrackerOptions& o = tracker_.options();
  const int64_t s = 1'000'000'000;                                // one second in nanoseconds
  EXPECT_FALSE(tracker_.RegistrationDue(100 * s, 10000, 10000));  // no plan
  tracker_.SetPlan(index_);
  EXPECT_FALSE(tracker_.RegistrationDue(100 * s, 10000, 10000));  // no alignment
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
  // A pick is checked on fewer points than a registered alignment is refined on.
  ASSERT_LT(o.check_min_points, o.min_points);
  EXPECT_EQ(tracker_.MinPoints(), o.check_min_points);
  EXPECT_TRUE(tracker_.RegistrationDue(10 * s, o.check_min_points, o.min_new_points));
  EXPECT_FALSE(tracker_.RegistrationDue(10 * s, o.check_min_points - 1, o.min_new_points));
  const std::vector<Eigen::Vector2d> cloud = Cloud();
  ASSERT_TRUE(tracker_.Offer(ResultFor(truth_, cloud), cloud, 1, 2).accepted);
  EXPECT_EQ(tracker_.MinPoints(), o.min_points);
  tracker_.MarkRegistrationStarted(10 * s);
  EXPECT_TRUE(tracker_.RegistrationDue(10 * s, o.min_points, o.min_new_points));
  EXPECT_FALSE(tracker_.RegistrationDue(10 * s, o.min_points - 1, o.min_new_points));
  EXPECT_FALSE(tracker_.RegistrationDue(10 * s, o.min_points, o.min_new_points - 1));
  EXPECT_FALSE(tracker_.RegistrationDue(100 * s, o.min_points, 0));  // nothing new
  // Few new points, but max_interval_s has passed since the last start.
  const auto interval = static_cast<int64_t>(o.max_interval_s * 1e9);
  EXPECT_FALSE(tracker_.RegistrationDue(10 * s + interval - 1, o.min_points, 1));
  EXPECT_TRUE(tracker_.RegistrationDue(10 * s + interval, o.min_points, 1));
}

// A wearer does not walk through walls: a step through the middle of a plan wall under
// the alignment in use flags UNRELIABLE until the alignment changes; a step that clips a
// wall's end (a door's jamb) by less than path_check_margin_m does not.
TEST_F(TrackerTest, APathThroughAWallIsUnreliable) {
  tracker_.SetPlan(index_);
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
  const Se2 T_slam_plan = truth_.Inverse();
  auto walk = [&](const std::vector<Eigen::Vector2d>& plan_points) {
    PlanPoseEstimate e;
    for (const Eigen::Vector2d& p : plan_points) e = tracker_.Correct({T_slam_plan * p, 0, 1.6});
    return e.reliability;
  };
  // The inner wall runs from (4, 0) to (4, 4.5): past its end at (4, 4.5), 0.2 m from it.
  Reliability r = walk({{3.0, 4.3}, {3.8, 4.3}, {4.2, 4.3}, {4.6, 4.3}});
  EXPECT_EQ(r.flag, ReliabilityFlag::kDegraded) << r.reason;
  // Back through its middle.
  r = walk({{4.2, 2.0}, {3.8, 2.0}, {3.4, 2.0}});
  EXPECT_EQ(r.flag, ReliabilityFlag::kUnreliable);
  EXPECT_THAT(r.reason, HasSubstr("crosses a wall"));
  // A new alignment starts clean.
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 2), "");
  EXPECT_EQ(walk({{3.0, 2.0}}).flag, ReliabilityFlag::kDegraded);
  // Without the check, the same walk is not flagged for it.
  TrackerOptions options;
  options.path_check = false;
  tracker_ = Tracker(options);
  tracker_.SetPlan(index_);
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
  EXPECT_EQ(walk({{4.2, 2.0}, {3.8, 2.0}}).flag, ReliabilityFlag::kDegraded);
}

// A registration refits the walls, not the walk: after a step through a wall, the flag
// stays while the walk of the registration's window goes through a wall under the new
// alignment too, and goes once it does not.
TEST_F(TrackerTest, APathThroughAWallStaysFlaggedUntilAnAlignmentWalksItClear) {
  const auto cloud = Cloud();
  const std::vector<Eigen::Vector2d> through = WalkAlongY2(2.1, 6.1);  // across the inner wall
  const std::vector<Eigen::Vector2d> clear = WalkAlongY2(5, 9);
  tracker_.SetPlan(index_);
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
  ASSERT_TRUE(tracker_.Offer(ResultFor(truth_, cloud), cloud, 1, 2, clear).accepted);
  for (const Eigen::Vector2d& p : through) tracker_.Correct({p, 0, 1.6});
  ASSERT_TRUE(tracker_.path_crossed());
  EXPECT_EQ(tracker_.CurrentReliability().flag, ReliabilityFlag::kUnreliable);

  Tracker::Decision d =
      tracker_.Offer(ResultFor(truth_, cloud), cloud, tracker_.alignment().version, 3, through);
  ASSERT_TRUE(d.accepted) << d.reason;
  EXPECT_TRUE(tracker_.path_crossed());
  EXPECT_THAT(tracker_.CurrentReliability().reason, HasSubstr("crosses a wall"));

  d = tracker_.Offer(ResultFor(truth_, cloud), cloud, tracker_.alignment().version, 4, clear);
  ASSERT_TRUE(d.accepted) << d.reason;
  EXPECT_FALSE(tracker_.path_crossed());
  EXPECT_NE(tracker_.CurrentReliability().flag, ReliabilityFlag::kUnreliable)
      << tracker_.CurrentReliability().reason;
}

// A pick is registered on check_min_points wall points, fewer than a place needs: the
// result is not taken (too few walls to place the wearer), but the pick is checked, and
// with the plan search on, a pick whose walls do not fit is UNRELIABLE at once.
TEST_F(TrackerTest, AWrongPickIsFlaggedOnAFewWalls) {
  TrackerOptions options;
  options.global_search = true;
  tracker_ = Tracker(options);
  tracker_.SetPlan(index_);
  const Se2 wrong = Se2{Deg(90), {3.0, -2.0}} * truth_;
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(wrong, {4, 2}, {1, 0}), 1), "");
  EXPECT_EQ(tracker_.CurrentReliability().flag, ReliabilityFlag::kDegraded);
  std::vector<Eigen::Vector2d> few;
  const std::vector<Eigen::Vector2d> cloud = Cloud();
  for (size_t i = 0; i < cloud.size() && few.size() < options.check_min_points; i += 37)
    few.push_back(cloud[i]);
  ASSERT_LT(few.size(), options.min_points);
  const Tracker::Decision d = tracker_.Offer(ResultFor(truth_, few), few, 1, 2);
  EXPECT_FALSE(d.accepted);
  EXPECT_THAT(d.reason, HasSubstr("few walls"));
  const Reliability r = tracker_.CurrentReliability();
  EXPECT_EQ(r.flag, ReliabilityFlag::kUnreliable);
  EXPECT_THAT(r.reason, HasSubstr("do not fit"));
  EXPECT_EQ(tracker_.alignment().source, AlignmentSource::kWallPick);
}

// A check on a few walls tells a pick whose walls do not fit; one whose walls fit is not
// placed by it (a wrong pick's few walls often fit too): DEGRADED until a registration.
TEST_F(TrackerTest, APickWhoseFewWallsFitIsNotReliableUntilARegistration) {
  tracker_.SetPlan(index_);
  const Se2 picked = Se2{Deg(0.5), {0.03, -0.02}} * truth_;
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(picked, {4, 2}, {1, 0}), 1), "");
  const std::vector<Eigen::Vector2d> cloud = Cloud();
  std::vector<Eigen::Vector2d> few;
  for (size_t i = 0; i < cloud.size() && few.size() < tracker_.options().check_min_points; i += 37)
    few.push_back(cloud[i]);
  for (int i = 0; i < 3; ++i) {
    const Tracker::Decision d =
        tracker_.Offer(ResultFor(truth_, few), few, tracker_.alignment().version, 2 + i);
    ASSERT_FALSE(d.accepted);
    EXPECT_THAT(d.reason, HasSubstr("few walls"));
  }
  tracker_.Correct({truth_.Inverse() * Eigen::Vector2d(2, 2), 0, 1.6});
  Reliability r = tracker_.CurrentReliability();
  EXPECT_EQ(r.flag, ReliabilityFlag::kDegraded);
  EXPECT_EQ(r.reason, "wall pick, not yet registered");

  // The same place registered on enough walls, again and again, is trusted.
  for (int i = 0; i < 5; ++i)
    ASSERT_TRUE(
        tracker_.Offer(ResultFor(truth_, cloud), cloud, tracker_.alignment().version, 10 + i)
            .accepted);
  tracker_.Correct({truth_.Inverse() * Eigen::Vector2d(2, 2.1), 0, 1.6});
  r = tracker_.CurrentReliability();
  EXPECT_EQ(r.flag, ReliabilityFlag::kReliable) << r.reason;
}

// A wrong pick 10 m off often puts the wearer outside the building, where the plan has no
// walls to check the walk against: off_plan_margin_m beyond the plan's box is UNRELIABLE.
TEST_F(TrackerTest, AWearerOutsideThePlanIsUnreliable) {
  TrackerOptions options;
  options.path_check = false;  // the walk below goes through the outer wall
  ASSERT_EQ(options.off_plan_margin_m, 1.0);
  const auto flag_at = [&](Tracker& tracker, const Eigen::Vector2d& plan_point) {
    tracker.Correct({truth_.Inverse() * plan_point, 0, 1.6});
    return tracker.CurrentReliability();
  };
  Tracker tracker(options);
  tracker.SetPlan(index_);
  ASSERT_EQ(tracker.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
  EXPECT_EQ(flag_at(tracker, {2, 2}).flag, ReliabilityFlag::kDegraded);
  // The plan spans (0, 0)-(10, 7): half a metre outside is within the margin.
  EXPECT_EQ(flag_at(tracker, {10.5, 7.5}).flag, ReliabilityFlag::kDegraded);
  const Reliability r = flag_at(tracker, {13, 9});
  EXPECT_EQ(r.flag, ReliabilityFlag::kUnreliable);
  EXPECT_EQ(r.reason, "outside the floor plan (3.6 m)");  // from the box's corner (10, 7)
  EXPECT_EQ(flag_at(tracker, {9, 6}).flag, ReliabilityFlag::kDegraded);  // back inside

  options.off_plan_margin_m = 0;
  Tracker unchecked(options);
  unchecked.SetPlan(index_);
  ASSERT_EQ(unchecked.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
  EXPECT_EQ(flag_at(unchecked, {13, 9}).flag, ReliabilityFlag::kDegraded);
}

// The search places a wearer from global_min_points wall points of its window, but
// checks an alignment in use (here a pick whose walls do not fit) from
// global_check_min_points: a wrong pick in a hall whose few walls are far away is searched
// for too.
TEST_F(TrackerTest, ASearchChecksAPickOnFewerWallsThanItPlacesOn) {
  TrackerOptions options;
  options.global_search = true;
  options.global_min_points = 150;
  options.global_check_min_points = 60;
  tracker_ = Tracker(options);
  EXPECT_FALSE(tracker_.GlobalSearchDue(1, 1000)) << "no plan";
  tracker_.SetPlan(index_);
  EXPECT_EQ(tracker_.GlobalMinPoints(), 150u);
  EXPECT_FALSE(tracker_.GlobalSearchDue(1, 149));
  EXPECT_TRUE(tracker_.GlobalSearchDue(1, 150));
  // A pick is the wearer's word: checked only once its walls do not fit it.
  const Se2 wrong = Se2{Deg(90), {3.0, -2.0}} * truth_;
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(wrong, {4, 2}, {1, 0}), 1), "");
  EXPECT_EQ(tracker_.GlobalMinPoints(), 60u);
  EXPECT_FALSE(tracker_.GlobalSearchDue(2, 1000));
  const std::vector<Eigen::Vector2d> cloud = Cloud();
  EXPECT_FALSE(tracker_.Offer(ResultFor(truth_, cloud), cloud, 1, 2).accepted);
  ASSERT_TRUE(tracker_.WallsDoNotFit());
  EXPECT_FALSE(tracker_.GlobalSearchDue(3, 59));
  EXPECT_TRUE(tracker_.GlobalSearchDue(3, 60));
}

// Placing waits global_interval_s between searches; a check of the place in use,
// global_check_interval_s (a wrong place is undone sooner).
TEST_F(TrackerTest, AChecksIntervalIsItsOwn) {
  TrackerOptions options;
  options.global_search = true;
  ASSERT_LT(options.global_check_interval_s, options.global_interval_s);
  tracker_ = Tracker(options);
  tracker_.SetPlan(index_);
  const int64_t s = 1'000'000'000;
  tracker_.MarkGlobalSearchStarted(10 * s);
  const auto after = [&](double seconds) {
    return tracker_.GlobalSearchDue(10 * s + static_cast<int64_t>(seconds * 1e9), 1000);
  };
  EXPECT_FALSE(after(options.global_check_interval_s));
  EXPECT_TRUE(after(options.global_interval_s));
  // A pick whose walls do not fit: checked every global_check_interval_s.
  const Se2 wrong = Se2{Deg(90), {3.0, -2.0}} * truth_;
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(wrong, {4, 2}, {1, 0}), 10 * s), "");
  const std::vector<Eigen::Vector2d> cloud = Cloud();
  tracker_.Offer(ResultFor(truth_, cloud), cloud, tracker_.alignment().version, 10 * s);
  ASSERT_TRUE(tracker_.WallsDoNotFit());
  EXPECT_FALSE(after(options.global_check_interval_s - 0.1));
  EXPECT_TRUE(after(options.global_check_interval_s));
}

// Two identical rooms 6 m apart: a registered alignment that would put the wearer in the
// other room (a better fit than a slightly-off one) is beyond the filter's gate; it is
// held until later results, over metres walked, keep landing on it (the navigation
// app's confirmation rule, made to need independent data).
TEST(TrackerJumpTest, FarJumpWaitsForConfirmation) {
  std::vector<Segment> walls;
  for (double x0 : {0.0, 6.0}) {
    walls.push_back({{x0, 0}, {x0 + 4, 0}});
    walls.push_back({{x0 + 4, 0}, {x0 + 4, 3}});
    walls.push_back({{x0 + 4, 3}, {x0, 3}});
    walls.push_back({{x0, 3}, {x0, 0}});
    walls.push_back({{x0 + 1, 0}, {x0 + 1, 1}});  // not symmetric within a room
  }
  auto plan = MakeFloorPlan("twins", walls);
  ASSERT_TRUE(plan.ok());
  Tracker tracker(TrackerOptions{});
  tracker.SetPlan(std::make_shared<const ClosestWallIndex>(plan.plan));
  // The wearer's walls: room A, in a slam frame equal to the plan frame.
  std::vector<Eigen::Vector2d> cloud;
  for (const Segment& s : std::vector<Segment>(walls.begin(), walls.begin() + 5))
    for (double u = 0; u <= 1; u += 0.01) cloud.push_back(s.a + u * (s.b - s.a));
  ASSERT_TRUE(tracker.ApplyWallPick(PickFor(Se2{0.02, {0.1, 0}}, {2, 0}, {0, 1}), 1).empty());
  tracker.Correct({{2, 1.5}, 0, 1.6});
  RegistrationResult near;
  near.T_plan_slam = Se2{0.0, {0.03, 0}};  // slightly off, better than the pick
  near.matched = static_cast<uint32_t>(cloud.size());
  ASSERT_TRUE(tracker.Offer(near, cloud, tracker.alignment().version, 2).accepted);
  tracker.Correct({{2, 1.5}, 0, 1.6});
  RegistrationResult far = near;
  far.T_plan_slam = Se2{0.0, {6, 0}};  // exact, but in room B: 6 m away
  const Tracker::Decision first = tracker.Offer(far, cloud, tracker.alignment().version, 3);
  EXPECT_FALSE(first.accepted);
  EXPECT_THAT(first.reason, HasSubstr("waits for confirmation"));
  // The same answer at once, from nearly the same data, is no confirmation.
  const Tracker::Decision again = tracker.Offer(far, cloud, tracker.alignment().version, 4);
  EXPECT_FALSE(again.accepted);
  // The wearer walks on (back and forth in the room) and the result stays: taken.
  const TrackerOptions& o = tracker.options();
  for (int step = 0; step * 0.5 <= o.confirm_walk_m; ++step)
    tracker.Correct({{2 + (step % 2 ? 0.5 : 0.0), 1.5}, 0, 1.6});
  const Tracker::Decision second = tracker.Offer(far, cloud, tracker.alignment().version, 5);
  EXPECT_TRUE(second.accepted) << second.reason;
  EXPECT_THAT(second.reason, HasSubstr("jump confirmed"));
  EXPECT_THAT(tracker.alignment().T_plan_slam, IsNearlySe2(far.T_plan_slam, 1e-9, 1e-9));
}

// Placement without a pick (issue 7): the decision on a search's refined places.
class GlobalPlacementDecisionTest : public TrackerTest {
 protected:
  GlobalPlacementDecisionTest() {
    TrackerOptions o;
    o.global_search = true;
    tracker_ = Tracker(o);
    tracker_.SetPlan(index_);
    // The truth fits the cloud to a few centimetres; a place 6 m off fits a third as well.
    truth_place_ = {truth_, 0.9, 0.0004, 0.98};
    other_place_ = {Se2{truth_.theta, truth_.t + Eigen::Vector2d(6, 0)}, 0.8, 0.0012, 0.9};
  }
  Tracker::Decision Offer(std::vector<GlobalPlace> places, int64_t stamp) {
    return tracker_.OfferPlaces(places, centre_, tracker_.alignment().version, stamp);
  }
  // A wall pick at the other place (6 m off) and the first registration on the walls,
  // which fit the truth: its decision in *registered.
  void PickWronglyAndRegister(Tracker::Decision* registered) {
    const Se2 wrong = other_place_.T_plan_slam;
    ASSERT_EQ(tracker_.ApplyWallPick(PickFor(wrong, {4, 2}, {1, 0}), 1), "");
    const std::vector<Eigen::Vector2d> cloud = Cloud();
    tracker_.Correct({{2.0, 1.5}, 0, 1.6});
    *registered = tracker_.Offer(ResultFor(wrong, cloud), cloud, tracker_.alignment().version, 2);
  }
  GlobalPlace truth_place_, other_place_;
  const Eigen::Vector2d centre_{1.0, 2.0};  // slam frame
};

TEST_F(GlobalPlacementDecisionTest,
       ASearchedPlacesFirstRegistrationNeedsFewerWallsToFitThanAPicks) {
  // A registration fitting 80% of the walls: refused after a pick (90%), as a place that
  // explains fewer of the walls than a pick's first place must; taken after a searched
  // place (75%), which a minute of walls put ahead of every other place of the plan (a
  // plan that lacks walls that stand leaves a right place's windows under 90%).
  const std::vector<Eigen::Vector2d> cloud = Cloud();
  RegistrationResult r = ResultFor(truth_, cloud);
  r.inliers = r.points * 4 / 5;
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
  tracker_.Correct({{2.0, 1.5}, 0, 1.6});
  const Tracker::Decision picked = tracker_.Offer(r, cloud, tracker_.alignment().version, 2);
  EXPECT_FALSE(picked.accepted);
  EXPECT_THAT(picked.reason, HasSubstr("too few wall points fit"));

  tracker_.Reset();
  ASSERT_FALSE(Offer({truth_place_, other_place_}, 3).accepted);
  ASSERT_TRUE(Offer({truth_place_, other_place_}, 4).accepted);
  ASSERT_EQ(tracker_.alignment().source, AlignmentSource::kGlobalSearch);
  tracker_.Correct({{2.0, 1.5}, 0, 1.6});
  const Tracker::Decision searched = tracker_.Offer(r, cloud, tracker_.alignment().version, 5);
  EXPECT_TRUE(searched.accepted) << searched.reason;
  EXPECT_THAT(searched.reason, Not(HasSubstr("too few wall points fit")));
  // ...but not from fewer than 75%.
  tracker_.Reset();
  ASSERT_FALSE(Offer({truth_place_, other_place_}, 6).accepted);
  ASSERT_TRUE(Offer({truth_place_, other_place_}, 7).accepted);
  r.inliers = r.points * 7 / 10;
  tracker_.Correct({{2.0, 1.5}, 0, 1.6});
  const Tracker::Decision fewer = tracker_.Offer(r, cloud, tracker_.alignment().version, 8);
  EXPECT_FALSE(fewer.accepted);
  EXPECT_THAT(fewer.reason, HasSubstr("too few wall points fit"));
}

TEST_F(GlobalPlacementDecisionTest, AClearPlaceIsTakenWhenTheNextSearchAgreesAndTrustedAfterThree) {
  EXPECT_THAT(tracker_.CurrentReliability().reason, HasSubstr("searching the plan"));
  // Clear of the next (a third of its error), but one search proves little.
  const Tracker::Decision first = Offer({truth_place_, other_place_}, 1);
  EXPECT_FALSE(first.accepted);
  EXPECT_FALSE(tracker_.has_alignment());
  // The same place clear again: taken, not yet RELIABLE.
  const Tracker::Decision second = Offer({truth_place_, other_place_}, 2);
  ASSERT_TRUE(second.accepted) << second.reason;
  EXPECT_EQ(tracker_.alignment().source, AlignmentSource::kGlobalSearch);
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(truth_, 1e-12, 1e-12));
  // The next search (a check) leads with the place in use: confirmed.
  const Tracker::Decision third = Offer({truth_place_, other_place_}, 3);
  EXPECT_FALSE(third.accepted);
  EXPECT_THAT(third.reason, HasSubstr("place confirmed"));
  EXPECT_EQ(tracker_.alignment().version, 1u);
}

TEST_F(GlobalPlacementDecisionTest, AnUnconfirmedPlaceIsNeverReliable) {
  ASSERT_FALSE(Offer({truth_place_, other_place_}, 1).accepted);
  ASSERT_TRUE(Offer({truth_place_, other_place_}, 2).accepted);
  // Registrations fit it perfectly...
  const std::vector<Eigen::Vector2d> cloud = Cloud();
  for (int i = 0; i < 6; ++i) {
    tracker_.Correct({{2.0 + 0.3 * i, 1.5}, 0, 1.6});
    tracker_.Offer(ResultFor(truth_, cloud), cloud, tracker_.alignment().version, 10 + i);
  }
  // ...yet until a search confirms the place, it is at best DEGRADED.
  EXPECT_NE(tracker_.CurrentReliability().flag, ReliabilityFlag::kReliable);
  EXPECT_THAT(tracker_.CurrentReliability().reason, HasSubstr("not yet confirmed"));
  // The registrations changed the alignment by centimetres: still the same place.
  GlobalPlace again = truth_place_;
  again.T_plan_slam = tracker_.alignment().T_plan_slam;
  EXPECT_THAT(Offer({again, other_place_}, 20).reason, HasSubstr("place confirmed"));
  EXPECT_EQ(tracker_.CurrentReliability().flag, ReliabilityFlag::kReliable);
}

TEST_F(GlobalPlacementDecisionTest, LookAlikePlacesAreNotTaken) {
  GlobalPlace twin = other_place_;
  twin.fit_mse = truth_place_.fit_mse * 1.03;  // fits as well, within global_min_lead
  for (int i = 0; i < 10; ++i) {
    const Tracker::Decision d = Offer({truth_place_, twin}, i);
    EXPECT_FALSE(d.accepted);
    EXPECT_THAT(d.reason, HasSubstr("ahead 0 searches"));
  }
  EXPECT_FALSE(tracker_.has_alignment());
  // Nor a place that fits too few of the walls, however clear.
  GlobalPlace poor = truth_place_;
  poor.inlier_ratio = 0.4;
  for (int i = 0; i < 5; ++i) EXPECT_FALSE(Offer({poor}, 20 + i).accepted);
  // A place that keeps the lead without being clear: taken after three searches.
  GlobalPlace runner_up = other_place_;
  runner_up.fit_mse = truth_place_.fit_mse * 1.5;
  EXPECT_FALSE(Offer({truth_place_, runner_up}, 30).accepted);
  EXPECT_FALSE(Offer({truth_place_, runner_up}, 31).accepted);
  EXPECT_TRUE(Offer({truth_place_, runner_up}, 32).accepted);
}

TEST_F(GlobalPlacementDecisionTest, APlaceALittleAheadSearchAfterSearchLeadsInTheEnd) {
  // A hall whose walls all look alike at a glance: the truth fits 15% better than the
  // next, search after search. Its leads multiply; once they reach what three leads of
  // 1 / global_lead_ratio would (1.25^3), it has led: taken, and confirmed.
  GlobalPlace twin = other_place_;
  twin.fit_mse = truth_place_.fit_mse * 1.15;
  for (int i = 0; i < 4; ++i) EXPECT_FALSE(Offer({truth_place_, twin}, i).accepted) << i;
  const Tracker::Decision d = Offer({truth_place_, twin}, 4);  // 1.15^5 = 2.01
  ASSERT_TRUE(d.accepted) << d.reason;
  EXPECT_THAT(d.reason, HasSubstr("ahead 5 searches in a row, leads multiplying to 2.0"));
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(truth_, 1e-12, 1e-12));
  // Another best in between starts the count over.
  tracker_.Reset();
  for (int i = 0; i < 4; ++i) EXPECT_FALSE(Offer({truth_place_, twin}, 10 + i).accepted);
  EXPECT_FALSE(Offer({twin, truth_place_}, 14).accepted);
  for (int i = 0; i < 4; ++i) EXPECT_FALSE(Offer({truth_place_, twin}, 15 + i).accepted);
  EXPECT_TRUE(Offer({truth_place_, twin}, 19).accepted);
  // A search where it stays first by less than global_min_lead neither counts nor
  // starts the count over.
  tracker_.Reset();
  GlobalPlace close = other_place_;
  close.fit_mse = truth_place_.fit_mse * 1.02;
  for (int i = 0; i < 2; ++i) EXPECT_FALSE(Offer({truth_place_, twin}, 30 + i).accepted);
  const Tracker::Decision tie = Offer({truth_place_, close}, 32);
  EXPECT_FALSE(tie.accepted);
  EXPECT_THAT(tie.reason, HasSubstr("ahead 2 searches in a row"));
  for (int i = 0; i < 2; ++i) EXPECT_FALSE(Offer({truth_place_, twin}, 33 + i).accepted);
  EXPECT_TRUE(Offer({truth_place_, twin}, 35).accepted);
}

TEST_F(GlobalPlacementDecisionTest, APlaceWithATwinTheWallsCannotTellApartNeverLeads) {
  // A hall that looks the same both ways round: the search finds the place and its
  // half-turn, under which the plan around the walk looks the same (RefinePlaces' alike
  // share). The one fits 15% better search after search, which in such a hall is the
  // drift's noise, not evidence: no lead counts while the twin is there (the default
  // global_alike_share, 0.9).
  GlobalPlace twin = other_place_;
  twin.fit_mse = truth_place_.fit_mse * 1.15;
  twin.alike = 0.98;
  for (int i = 0; i < 8; ++i) {
    const Tracker::Decision d = Offer({truth_place_, twin}, i);
    EXPECT_FALSE(d.accepted) << i;
    EXPECT_THAT(d.reason, HasSubstr("looks the same from the walk (98% of the walls in sight)"));
  }
  EXPECT_FALSE(tracker_.has_alignment());
  // Twice as good is not enough against a twin (global_twin_clear_ratio: the drift makes
  // twins fit that far apart). A twin it is clear of at four times (the walk left the
  // symmetric part of the hall: the walls tell them apart after all) does not hold it
  // back; nor does a place where the plan looks different (under global_alike_share).
  twin.fit_mse = truth_place_.fit_mse * 2.5;
  for (int i = 0; i < 4; ++i) EXPECT_FALSE(Offer({truth_place_, twin}, 8 + i).accepted) << i;
  twin.fit_mse = truth_place_.fit_mse * 4.5;
  EXPECT_FALSE(Offer({truth_place_, twin}, 12).accepted);
  EXPECT_TRUE(Offer({truth_place_, twin}, 13).accepted);
  tracker_.Reset();
  twin.fit_mse = truth_place_.fit_mse * 1.3;
  twin.alike = 0.8;
  for (int i = 0; i < 2; ++i) EXPECT_FALSE(Offer({truth_place_, twin}, 20 + i).accepted);
  EXPECT_TRUE(Offer({truth_place_, twin}, 22).accepted);  // 1.3^3 = 2.2
}

TEST_F(GlobalPlacementDecisionTest, ASearchWhoseGridWasCrowdedDoesNotCount) {
  // The grid returned as many places as it may, all scoring within 2% of the best: the
  // true place may be among those it left out, so the refined best's lead (however
  // clear) does not count (the default global_crowded_ratio, 0.98). With places spread
  // out, it does.
  const std::vector<double> crowded(12, 0.9), spread = {0.9, 0.85, 0.8, 0.8};
  for (int i = 0; i < 5; ++i) {
    const Tracker::Decision d =
        tracker_.OfferPlaces({truth_place_, other_place_}, centre_, 0, i, crowded);
    EXPECT_FALSE(d.accepted) << i;
    EXPECT_THAT(d.reason, HasSubstr("the grid's 12 places all score within 0% of the best"));
  }
  EXPECT_FALSE(tracker_.OfferPlaces({truth_place_, other_place_}, centre_, 0, 10, spread).accepted);
  EXPECT_TRUE(tracker_.OfferPlaces({truth_place_, other_place_}, centre_, 0, 11, spread).accepted);
  // A crowded search in between neither counts nor starts the row of leads over.
  tracker_.Reset();
  EXPECT_FALSE(tracker_.OfferPlaces({truth_place_, other_place_}, centre_, 0, 20, spread).accepted);
  EXPECT_FALSE(
      tracker_.OfferPlaces({truth_place_, other_place_}, centre_, 0, 21, crowded).accepted);
  const Tracker::Decision after =
      tracker_.OfferPlaces({truth_place_, other_place_}, centre_, 0, 22, spread);
  EXPECT_THAT(after.reason, HasSubstr("ahead 2 searches in a row"));
}

TEST_F(GlobalPlacementDecisionTest, OnlyAPlaceThatFitsAndWalksClearLeads) {
  // The best place walks the wearer through walls or fits too few of them (RefinePlaces
  // ranks it 2, with every other place): however clear its fit, it never leads.
  GlobalPlace walker = truth_place_, twin = other_place_;
  walker.rank = twin.rank = 2;
  for (int i = 0; i < 5; ++i) {
    const Tracker::Decision d = Offer({walker, twin}, 1 + i);
    EXPECT_FALSE(d.accepted);
    EXPECT_THAT(d.reason, HasSubstr("ahead 0 searches"));
  }
  EXPECT_FALSE(tracker_.has_alignment());
  // A look-alike that walks through walls (rank 1) is still a rival on the walls: a
  // place that alone walks clear is too often a look-alike whose true twin the search
  // did not return. Fitting nearly as well, it keeps the truth from leading...
  twin.rank = 1;
  twin.fit_mse = truth_place_.fit_mse * 1.03;
  for (int i = 0; i < 5; ++i) EXPECT_FALSE(Offer({truth_place_, twin}, 10 + i).accepted);
  // ...and fitting clearly worse, it does not.
  twin.fit_mse = truth_place_.fit_mse * 3;
  EXPECT_FALSE(Offer({truth_place_, twin}, 20).accepted);
  EXPECT_TRUE(Offer({truth_place_, twin}, 21).accepted);
}

// Where the plan lacks walls that stand, the true place fits half of the walls and the
// others less: it may lead from global_place_min_inliers (0.45), not only from the 60%
// under which the walls "do not fit" an alignment in use.
TEST_F(GlobalPlacementDecisionTest, APlaceFittingHalfTheWallsOfAPlanThatLacksSomeCanLead) {
  ASSERT_LT(tracker_.options().global_place_min_inliers, 0.5);
  ASSERT_GT(tracker_.options().global_min_inliers, 0.5);
  GlobalPlace half = truth_place_, less = other_place_;
  half.inlier_ratio = 0.5;
  less.inlier_ratio = 0.35;
  EXPECT_FALSE(Offer({half, less}, 1).accepted);
  const Tracker::Decision taken = Offer({half, less}, 2);
  EXPECT_TRUE(taken.accepted) << taken.reason;

  TrackerOptions o = tracker_.options();
  o.global_place_min_inliers = 0.6;
  tracker_ = Tracker(o);
  tracker_.SetPlan(index_);
  for (int i = 0; i < 5; ++i) EXPECT_FALSE(Offer({half, less}, 10 + i).accepted);
  EXPECT_FALSE(tracker_.has_alignment());
}

TEST_F(GlobalPlacementDecisionTest, AWrongPickIsReplacedByAPlaceThatKeepsWinning) {
  // The pick put the wearer 6 m off (the other place); the walls fit the truth. The
  // first registration finds the walls do not fit the pick: UNRELIABLE at once.
  Tracker::Decision registered;
  ASSERT_NO_FATAL_FAILURE(PickWronglyAndRegister(&registered));
  EXPECT_FALSE(registered.accepted);
  EXPECT_TRUE(tracker_.WallsDoNotFit());
  EXPECT_EQ(tracker_.CurrentReliability().flag, ReliabilityFlag::kUnreliable);
  EXPECT_THAT(tracker_.CurrentReliability().reason, HasSubstr("walls do not fit"));
  GlobalPlace in_use = other_place_;
  in_use.fit_mse = 0.01;  // the place in use, refined: it fits badly
  in_use.inlier_ratio = 0.3;
  EXPECT_FALSE(Offer({truth_place_, in_use}, 2).accepted);
  EXPECT_FALSE(Offer({truth_place_, in_use}, 3).accepted);
  const Tracker::Decision third = Offer({truth_place_, in_use}, 4);
  ASSERT_TRUE(third.accepted) << third.reason;
  EXPECT_THAT(third.reason, HasSubstr("relocated"));
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(truth_, 1e-12, 1e-12));
  EXPECT_EQ(tracker_.alignment().source, AlignmentSource::kGlobalSearch);
}

TEST_F(GlobalPlacementDecisionTest, APickWhoseWallsDoNotFitGivesWayToAPlaceThatLeadsIt) {
  // A wrong pick whose walls do not fit (UNRELIABLE) is no better than no place: a place
  // that has led and fits better by a lead replaces it, clear or not.
  Tracker::Decision registered;
  ASSERT_NO_FATAL_FAILURE(PickWronglyAndRegister(&registered));
  ASSERT_TRUE(tracker_.WallsDoNotFit());
  GlobalPlace in_use = other_place_;
  in_use.fit_mse = truth_place_.fit_mse * 1.5;  // the pick refined: a lead behind, not 2
  EXPECT_FALSE(Offer({truth_place_, in_use}, 3).accepted);
  EXPECT_FALSE(Offer({truth_place_, in_use}, 4).accepted);
  const Tracker::Decision d = Offer({truth_place_, in_use}, 5);
  ASSERT_TRUE(d.accepted) << d.reason;
  EXPECT_THAT(d.reason, HasSubstr("relocated (the place in use fits 1.5 times worse)"));
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(truth_, 1e-12, 1e-12));
}

TEST_F(GlobalPlacementDecisionTest, ThePlaceInUseStaysAgainstATieAndStaleSearches) {
  ASSERT_EQ(tracker_.ApplyWallPick(PickFor(truth_, {4, 2}, {1, 0}), 1), "");
  GlobalPlace twin = other_place_;
  twin.fit_mse = truth_place_.fit_mse * 0.9;  // a look-alike fits marginally better
  for (int i = 0; i < 10; ++i) EXPECT_FALSE(Offer({twin, truth_place_}, 2 + i).accepted);
  EXPECT_THAT(tracker_.alignment().T_plan_slam, IsNearlySe2(truth_, 1e-12, 1e-12));
  // Nor does a place that fits the window clearly better replace a pick whose walls the
  // registrations find fitting: a look-alike, not a recovery.
  const std::vector<Eigen::Vector2d> cloud = Cloud();
  tracker_.Correct({{2.0, 1.5}, 0, 1.6});
  tracker_.Offer(ResultFor(truth_, cloud), cloud, tracker_.alignment().version, 20);
  ASSERT_FALSE(tracker_.WallsDoNotFit());
  twin.fit_mse = truth_place_.fit_mse * 0.3;
  for (int i = 0; i < 5; ++i) {
    const Tracker::Decision d = Offer({twin, truth_place_}, 30 + i);
    EXPECT_FALSE(d.accepted);
    if (i >= 2) {
      EXPECT_THAT(d.reason, HasSubstr("still fits the walls"));
    }
  }
  // A search made under an alignment since replaced says nothing.
  EXPECT_THAT(tracker_.OfferPlaces({other_place_}, centre_, 0, 40).reason,
              HasSubstr("alignment changed"));
}

}  // namespace
}  // namespace floorpose
