// The MCL estimator's parts (core/tracking/): KLD-sampling's count, resampling, the
// measurement model and its expected fit, and the estimator placing, tracking and
// recovering on a room, driven with injected stamps.
#include "core/tracking/mcl.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/random.h"
#include "tests/test_util.h"

namespace floorpose::tracking {
namespace {

using floorpose::testing::Deg;

TEST(KldSamplesTest, GrowsWithTheBinsTheBeliefCovers) {
  EXPECT_EQ(KldSamples(1, 0.05), 1u);
  // Fox 2003 eq. 12 for k = 100 bins: 99 / 0.1 (1 - 2/891 + sqrt(2/891) 2.326)^3.
  EXPECT_NEAR(static_cast<double>(KldSamples(100, 0.05)), 1347, 1);
  EXPECT_LT(KldSamples(10, 0.05), KldSamples(100, 0.05));
  EXPECT_GT(KldSamples(10, 0.01), KldSamples(10, 0.05));
}

TEST(BeliefTest, ResamplingKeepsTheWeightAndShrinksWhenConverged) {
  SplitMix64 rng(3);
  Belief b;
  // Two places 5 m apart, each well inside one KLD bin, the second three times as heavy.
  const Se2 a{0.1, {0.25, 0.25}}, c{0.1, {5.25, 0.25}};
  b.AddGaussian(a, Eigen::Vector3d(1e-6, 1e-4, 1e-4).asDiagonal(), a.t, 1000, std::log(1.0), rng);
  b.AddGaussian(c, Eigen::Vector3d(1e-6, 1e-4, 1e-4).asDiagonal(), c.t, 1000, std::log(3.0), rng);
  b.Normalize();
  EXPECT_NEAR(b.MassWithin({0, 0}, c.t, 1.0), 0.75, 1e-9);
  SampleBounds bounds;
  bounds.min_samples = 50;
  b.Resample(bounds, {0, 0}, rng);
  // Both places lie within a few bins: far fewer samples, the same split.
  EXPECT_EQ(b.size(), std::max(bounds.min_samples, KldSamples(2, bounds.kld_error)));
  EXPECT_NEAR(b.MassWithin({0, 0}, c.t, 1.0), 0.75, 0.1);
  const Mode m = b.LeadingMode({0, 0}, 1.0, Deg(10));
  EXPECT_NEAR(m.T_plan_slam.t.x(), 5.25, 0.05);
  EXPECT_NEAR(m.mass, 0.75, 0.1);
}

TEST(BeliefTest, TheEstimateMinimizesTheExpectedErrorAtTheWearer) {
  SplitMix64 rng(5);
  Belief b;
  // A pick's prior, spread by 1.5 m (60% of the mass), and a tight place 20 m off (40%).
  const Se2 pick{0, {0, 0}}, far{0, {20, 0}};
  b.AddGaussian(pick, Eigen::Vector3d(1e-4, 2.25, 2.25).asDiagonal(), pick.t, 600, 0.0, rng);
  b.AddGaussian(far, Eigen::Vector3d(1e-6, 1e-4, 1e-4).asDiagonal(), far.t, 400, 0.0, rng);
  b.Normalize();
  // Within 1 m the tight place holds the most...
  EXPECT_NEAR(b.LeadingMode({0, 0}, 1.0, Deg(10)).T_plan_slam.t.x(), 20.0, 0.1);
  // ...but the wearer is on average nearest a point of the cloud: its median towards the
  // far place, where 50% of the mass lies on either side (1.45 m along, 0.97 sigma).
  const Mode m = b.Estimate({0, 0}, 1.0, Deg(10));
  EXPECT_LT(m.T_plan_slam.t.norm(), 2.0);
  EXPECT_GT(m.mass, 0.05);
  // One place: the estimate is that place.
  Belief one;
  one.AddGaussian(far, Eigen::Vector3d(1e-6, 1e-4, 1e-4).asDiagonal(), far.t, 100, 0.0, rng);
  EXPECT_NEAR((one.Estimate({0, 0}, 1.0, Deg(10)).T_plan_slam.t - far.t).norm(), 0.0, 0.05);
  EXPECT_EQ(Belief().Estimate({0, 0}, 1.0, Deg(10)).mass, 0.0);
}

TEST(BeliefTest, MixingOffersTheShareAndKeepsTheRest) {
  SplitMix64 rng(4);
  Belief b;
  const Se2 held{0, {0, 0}}, offered{0, {5, 0}}, other{0, {-5, 0}};
  b.AddGaussian(held, Eigen::Vector3d(1e-6, 1e-4, 1e-4).asDiagonal(), held.t, 400, 0.0, rng);
  b.Mix({offered, other}, {0.0, 0.0}, PlaceCovariance(0.05, Deg(1)), {0, 0}, 0.2, 10, rng);
  EXPECT_NEAR(b.MassWithin({0, 0}, held.t, 1.0), 0.8, 1e-9);
  EXPECT_NEAR(b.MassWithin({0, 0}, offered.t, 1.0), 0.1, 1e-9) << "the share, split evenly";
  EXPECT_NEAR(b.MassWithin({0, 0}, other.t, 1.0), 0.1, 1e-9);
  EXPECT_EQ(b.size(), 400u + 2 * 40u) << "samples in proportion to the share";
  // Weighted: three times the likelihood, three times the share.
  Belief c;
  c.AddGaussian(held, Eigen::Vector3d(1e-6, 1e-4, 1e-4).asDiagonal(), held.t, 400, 0.0, rng);
  c.Mix({offered, other}, {std::log(3.0), 0.0}, PlaceCovariance(0.05, Deg(1)), {0, 0}, 0.2, 10,
        rng);
  EXPECT_NEAR(c.MassWithin({0, 0}, held.t, 1.0), 0.8, 1e-9);
  EXPECT_NEAR(c.MassWithin({0, 0}, offered.t, 1.0), 0.15, 1e-9);
  EXPECT_NEAR(c.MassWithin({0, 0}, other.t, 1.0), 0.05, 1e-9);
}

TEST(MeasurementModelTest, NearWallsIsLikelierAndFarIsClutter) {
  MeasurementModel m;
  EXPECT_GT(m.PointLogLikelihood(0.0, 3.0), m.PointLogLikelihood(0.2, 3.0));
  EXPECT_GT(m.PointLogLikelihood(0.2, 3.0), m.PointLogLikelihood(1.0, 3.0));
  // Beyond a few sigmas only clutter explains a point, at its rate over the reach.
  EXPECT_NEAR(m.PointLogLikelihood(1.0, 3.0), std::log(m.clutter / 3.0), 1e-6);
  EXPECT_NEAR(m.PointLogLikelihood(10.0, 3.0), std::log(m.clutter / 3.0), 1e-12);
  // The fit expected of a right alignment lies between a perfect one and clutter alone.
  const double expected = ExpectedLogLikelihood(m, 3.0);
  EXPECT_LT(expected, m.PointLogLikelihood(0.0, 3.0));
  EXPECT_GT(expected, m.PointLogLikelihood(1.0, 3.0));
}

// From ClutterOnlyFromM on, a point's log-likelihood is clutter's to the last bit, and
// not much sooner: MeanLogLikelihood may skip the closest wall of such points.
TEST(MeasurementModelTest, ClutterOnlyFromIsExactAndTight) {
  for (const double sigma : {0.03, 0.1, 0.3})
    for (const double clutter : {0.01, 0.2, 0.7})
      for (const double reach : {1.0, 3.0}) {
        MeasurementModel m;
        m.sigma_m = sigma;
        m.clutter = clutter;
        const double from = m.ClutterOnlyFromM(reach);
        const double far = m.PointLogLikelihood(2 * reach, reach);
        for (double d = from; d <= reach; d += 0.001)
          ASSERT_EQ(m.PointLogLikelihood(d, reach), far) << sigma << " " << clutter << " " << d;
        if (from < reach) {
          EXPECT_NE(m.PointLogLikelihood(0.9 * from, reach), far);
        }
      }
}

// MeanLogLikelihood gives the mean of PointLogLikelihood at every point's distance, from
// its table within 3e-6 a point (exactly for points it knows are clutter, for which it
// looks up no closest wall), at every noise and clutter.
TEST(MeasurementModelTest, MeanLogLikelihoodIsThePointsMean) {
  const ClosestWallIndex index(floorpose::testing::AsymmetricRoom());
  const double reach = index.max_distance_m();
  SplitMix64 rng(17);
  for (const double sigma : {0.03, 0.1, 0.3}) {
    for (const double clutter : {0.01, 0.2, 0.7}) {
      MeasurementModel m;
      m.sigma_m = sigma;
      m.clutter = clutter;
      for (int trial = 0; trial < 5; ++trial) {
        std::vector<Eigen::Vector2d> points;
        for (int i = 0; i < 500; ++i)
          points.push_back(floorpose::testing::RandomVector2(rng, {-5, -5}, {15, 12}));
        const Se2 T = floorpose::testing::RandomSe2(rng, M_PI, 3.0);
        double sum = 0;
        for (const Eigen::Vector2d& p : points) {
          const double d = index.Distance(T * p);
          const double exact = m.PointLogLikelihood(d <= reach ? d : 2 * reach, reach);
          ASSERT_NEAR(m.MeanLogLikelihood({p}, T, index, reach), exact, 3e-6)
              << sigma << " " << clutter << " " << d;
          sum += exact;
        }
        EXPECT_NEAR(m.MeanLogLikelihood(points, T, index, reach), sum / points.size(), 3e-6);
      }
    }
  }
}

TEST(MeasurementModelTest, WhatWasInSightPricesPlanWallsTheMeshLacksAndTheReverse) {
  const ClosestWallIndex index(floorpose::testing::AsymmetricRoom());
  MeasurementModel m;
  // The wearer walks along y = 1, a metre from the bottom wall, in the room's left part;
  // the mesh shows the bottom wall only.
  const std::vector<Eigen::Vector2d> walk = {{1, 1}, {2, 1}, {3, 1}};
  std::vector<Eigen::Vector2d> mesh;
  for (double x = 0; x <= 4; x += 0.1) mesh.push_back({x, 0});
  const std::vector<double> nearest = NearestWallPoint(walk, mesh);
  EXPECT_THAT(nearest, ::testing::Each(::testing::DoubleNear(1.0, 1e-9)));
  const double agree = std::log1p(-m.clutter), disagree = std::log(m.clutter);
  // Right: the bottom wall is the nearest plan wall, as far as in the mesh.
  EXPECT_NEAR(SightLogLikelihood(m, walk, nearest, Se2{0, {0, 0}}, index).log_likelihood, 3 * agree,
              1e-12);
  // 0.6 m lower, the plan's bottom wall is 0.4 m off the walk, the mesh's 1 m.
  EXPECT_NEAR(SightLogLikelihood(m, walk, nearest, Se2{0, {0, -0.6}}, index).log_likelihood,
              3 * disagree, 1e-12);
  // In the middle of the right part no plan wall is in sight: the mesh's wall a metre
  // off disagrees, and a mesh with none in sight agrees.
  const std::vector<Eigen::Vector2d> two = {{1, 1}, {2, 1}};  // to (6.6, 2.5) and (7.6, 2.5)
  const Se2 open{0, {5.6, 1.5}};
  EXPECT_NEAR(SightLogLikelihood(m, two, NearestWallPoint(two, mesh), open, index).log_likelihood,
              2 * disagree, 1e-12);
  EXPECT_NEAR(SightLogLikelihood(m, two, NearestWallPoint(two, {}), open, index).log_likelihood,
              2 * agree, 1e-12);
  EXPECT_EQ(SightLogLikelihood(m, {}, {}, open, index).asked, 0u) << "no positions";
  // A position on a plan wall is a walk through it, the motion model's to price: not asked.
  const std::vector<Eigen::Vector2d> through = {{1, 0.1}, {2, 1}};
  const SightFit fit =
      SightLogLikelihood(m, through, NearestWallPoint(through, mesh), Se2{0, {0, 0}}, index);
  EXPECT_EQ(fit.asked, 1u);
  EXPECT_NEAR(fit.log_likelihood, agree, 1e-12);
}

TEST(MotionModelTest, AWalkThroughAPlanWallCostsThroughWallPerWall) {
  const ClosestWallIndex index(floorpose::testing::AsymmetricRoom());
  MotionModel motion;
  // Three metres along the room's left part: short of the inner wall at x = 4 under one
  // alignment, across it under another a metre to the right.
  const std::vector<Eigen::Vector2d> path_slam = {{0.5, 1}, {1.5, 1}, {2.5, 1}, {3.5, 1}};
  const Se2 beside{0, {0, 0}}, through{0, {1, 0}};
  EXPECT_EQ(motion.PathLogPrior(path_slam, beside, index), 0.0);
  EXPECT_NEAR(motion.PathLogPrior(path_slam, through, index), std::log(motion.through_wall), 1e-12)
      << "one wall crossed, once";
  EXPECT_EQ(motion.PathLogPrior({{0.5, 1}}, through, index), 0.0) << "no step";
}

TEST(RecoveryTest, AFitLikeARandomPlaceKeepsTheDoubtAndARightOneClearsIt) {
  MeasurementModel m;
  const ClosestWallIndex index(floorpose::testing::AsymmetricRoom());
  const double random = RandomLogLikelihood(m, index);
  const double expected = ExpectedLogLikelihood(m, index.max_distance_m());
  EXPECT_LT(random, expected);
  Recovery right({}, m, index, 1.0, kPlaceRad);
  EXPECT_NEAR(right.Elsewhere(), 0.5, 1e-9) << "a start is doubted";
  EXPECT_FALSE(right.searched());
  right.Observe(expected, expected, 10.0, 1.0);
  EXPECT_LT(right.Elsewhere(), 0.01)
      << "left: the odds that another place of the plan fits as well";
  right.Searched();
  EXPECT_LT(right.Elsewhere(), 1e-6) << "a search found no other";
  right.Reset();
  EXPECT_FALSE(right.searched()) << "every start is checked by a search of its own";
  Recovery wrong({}, m, index, 1.0, kPlaceRad);
  for (int i = 0; i < 5; ++i) wrong.Observe(random, random, 1.0, 1.0);
  EXPECT_GT(wrong.Elsewhere(), 0.5) << "a fit no better than chance never clears the doubt";
  // A plan half unlike the building: worse than expected, far better than chance.
  Recovery stale({}, m, index, 1.0, kPlaceRad);
  for (int i = 0; i < 5; ++i)
    stale.Observe(0.5 * (expected + random), 0.5 * (expected + random), 1.0, 1.0);
  EXPECT_LT(stale.Elsewhere(), 0.01);
}

TEST(RecoveryTest, PlanPlacesAreTheAreaInDiscsTimesTheHeadings) {
  // 10 m x 7 m, every point within the index's reach (3 m) of a wall.
  const ClosestWallIndex index(floorpose::testing::AsymmetricRoom());
  EXPECT_NEAR(PlanPlaces(index, 1.0, kPlaceRad), 70 / M_PI * M_PI / kPlaceRad, 1e-6);
  EXPECT_NEAR(PlanPlaces(index, 2.0, kPlaceRad), 70 / (4 * M_PI) * M_PI / kPlaceRad, 1e-6);
  EXPECT_EQ(PlanPlaces(index, 100.0, M_PI), 1.0) << "never fewer than one";
}

TEST(RecoveryTest, ANearMissIsDoubtedUntilASearchHandsItsPlaceToTheBelief) {
  MeasurementModel m;
  const ClosestWallIndex index(floorpose::testing::AsymmetricRoom());
  const double expected = ExpectedLogLikelihood(m, index.max_distance_m());
  const double random = RandomLogLikelihood(m, index);
  Recovery r({}, m, index, 1.0, kPlaceRad);
  r.Searched();
  for (int i = 0; i < 20; ++i) r.Observe(expected, expected, 0.5, 1.0);
  ASSERT_LT(r.Elsewhere(), 1e-3);
  // Then the walls fit worse than they did, though better than at a random place: a
  // heading wrong after a jump, nearer a random place's fit than a right one's. Another
  // place of the plan would fit them as before.
  const double near_miss = random + 0.1 * (expected - random);
  int updates = 0;
  while (r.Elsewhere() < 0.5 && updates < 100) r.Observe(near_miss, near_miss, 0.5, 1.0), ++updates;
  EXPECT_LT(updates, 60) << "doubted within 60 updates";
  // Walls that fit nearer a right place than a random one are a right place's in a
  // building less like its plan (clutter, a wall moved), not a sign of a loss.
  Recovery cluttered({}, m, index, 1.0, kPlaceRad);
  cluttered.Searched();
  for (int i = 0; i < 20; ++i) cluttered.Observe(expected, expected, 0.5, 1.0);
  const double clutter = random + 0.6 * (expected - random);
  for (int i = 0; i < 100; ++i) cluttered.Observe(clutter, clutter, 0.5, 1.0);
  EXPECT_LT(cluttered.Elsewhere(), 0.01);
  // A search finds the places that fit; they join the belief, which takes their share.
  r.Searched();
  EXPECT_LT(r.Elsewhere(), 0.01);
  // A building less like its plan from the start sets its own level: no doubt from it.
  Recovery stale({}, m, index, 1.0, kPlaceRad);
  stale.Searched();
  for (int i = 0; i < 100; ++i) stale.Observe(clutter, clutter, 0.5, 1.0);
  EXPECT_LT(stale.Elsewhere(), 0.01);
}

TEST(RecoveryTest, PlacesASearchFoundAndTheBeliefLacksStayElsewhereUntilTheNextSearch) {
  MeasurementModel m;
  const ClosestWallIndex index(floorpose::testing::AsymmetricRoom());
  const double expected = ExpectedLogLikelihood(m, index.max_distance_m());
  Recovery r({}, m, index, 1.0, kPlaceRad);
  r.Searched(0.3);  // a crowd of look-alikes, 30% of it beyond what the belief took
  EXPECT_NEAR(r.Elsewhere(), 0.3 + 0.7 * 0.5, 0.01) << "the start's doubt of a random place stays";
  // Walls that fit as a right place does clear the doubt of a random place, but fit a
  // look-alike the belief lacks just as well.
  for (int i = 0; i < 20; ++i) r.Observe(expected, expected, 0.5, 1.0);
  EXPECT_NEAR(r.Elsewhere(), 0.3, 0.01);
  EXPECT_NEAR(r.Unheld(), 0.3, 0.01);
  // A loss adds to the doubt; the look-alikes keep their share of the rest.
  r.Observe(expected, expected, 0.0, 60.0);
  EXPECT_GT(r.Elsewhere(), 0.3);
  // The next search finds no place the belief does not hold: the loss's doubt is left.
  r.Searched(0);
  EXPECT_LT(r.Elsewhere(), 0.1);
}

TEST(RecoveryTest, SearchesComeAsOftenAsTheWearerMayBeElsewhere) {
  MeasurementModel m;
  const ClosestWallIndex index(floorpose::testing::AsymmetricRoom());
  RecoveryOptions o;
  o.search_share = 0.2;  // every 3 s at 20%
  o.search_interval_s = 3.0;
  Recovery r(o, m, index, 1.0, kPlaceRad);
  ASSERT_NEAR(r.Elsewhere(), 0.5, 1e-9);
  EXPECT_FALSE(r.SearchDue(2.9)) << "never more often than search_interval_s";
  EXPECT_TRUE(r.SearchDue(3.0));
  // Fits halfway between a right place and a random one bring the doubt down to a few
  // percent: a search is due after 0.2 * 3 / Elsewhere() seconds.
  const double mid =
      0.5 * (ExpectedLogLikelihood(m, index.max_distance_m()) + RandomLogLikelihood(m, index));
  int updates = 0;
  while (r.Elsewhere() > 0.02 && updates < 1000) r.Observe(mid, mid, 0.5, 1.0), ++updates;
  ASSERT_LE(r.Elsewhere(), 0.02) << "still doubted after " << updates << " updates";
  const double due_s = o.search_share * o.search_interval_s / r.Elsewhere();
  EXPECT_GT(due_s, 30.0);
  EXPECT_FALSE(r.SearchDue(0.99 * due_s));
  EXPECT_TRUE(r.SearchDue(1.01 * due_s));
}

TEST(ReliabilityTest, TheReasonNamesTheTermThatKeepsTheProbabilityDown) {
  const PublishOptions o;
  BeliefSummary s;
  s.mass_within = 1.0;
  s.checked = true;
  EXPECT_EQ(Assess(s, o).flag, ReliabilityFlag::kReliable);
  EXPECT_EQ(Assess(s, o).reason, "");
  // The doubt dominates while the latest walls fit like a right place's (231% of the
  // expected): the doubt is the start's, not the walls'.
  s.elsewhere = 0.6;
  s.fit_ratio = 2.31;
  s.searched = false;
  EXPECT_EQ(Assess(s, o).reason,
            "no search has confirmed the place (60% that the wearer is elsewhere)");
  s.searched = true;
  EXPECT_EQ(Assess(s, o).reason, "the place is still in doubt (60% that the wearer is elsewhere)");
  s.crowded = true;  // most of it at places a search found and the belief could not take
  EXPECT_EQ(Assess(s, o).reason,
            "more places fit than the belief holds (60% that the wearer is elsewhere)");
  s.crowded = false;
  s.fits = false;
  s.fit_ratio = 0.2;
  EXPECT_EQ(Assess(s, o).reason, "the walls fit the plan poorly (20% of the expected fit)");
  // The belief's own spread dominates.
  s.elsewhere = 0.05;
  s.mass_within = 0.7;
  EXPECT_EQ(Assess(s, o).reason, "uncertain: 70% of the belief within 1 m");
  s.places = 3;
  EXPECT_EQ(Assess(s, o).reason, "3 places fit (70% of the belief here)");
  s.checked = false;
  EXPECT_EQ(Assess(s, o).reason, "not yet checked against the walls (70% within 1 m)");
}

TEST(RecoveryTest, TheLatestFitIsReadAgainstTheMidpointOfRightAndRandom) {
  MeasurementModel m;
  const ClosestWallIndex index(floorpose::testing::AsymmetricRoom());
  Recovery r({}, m, index, 1.0, kPlaceRad);
  EXPECT_TRUE(r.Fits()) << "a start fits as expected until walls say otherwise";
  r.Observe(r.MidFit() - 0.01, r.MidFit() - 0.01, 0.5, 1.0);
  EXPECT_FALSE(r.Fits());
  r.Observe(r.MidFit() + 0.01, r.MidFit() + 0.01, 0.5, 1.0);
  EXPECT_TRUE(r.Fits());
}

// A walk in the asymmetric room: wall points seen from the wearer within 4 m (slam
// frame, T_plan_slam = truth), stamped a second apart.
struct RoomWalk {
  FloorPlan plan = floorpose::testing::AsymmetricRoom();
  std::shared_ptr<const ClosestWallIndex> index = std::make_shared<ClosestWallIndex>(plan);
  Se2 truth{Deg(30), {3, -2}};
  std::vector<Eigen::Vector2d> walls_plan = floorpose::testing::SampleWalls(plan, 0.05);

  // A gaze pick at plan_point on a wall facing -x, as the headset sees it under T.
  static WallPick PickOn(const Se2& T_plan_slam, const Eigen::Vector2d& plan_point) {
    const Eigen::Vector2d normal(-1, 0);
    return {T_plan_slam.Inverse() * plan_point, T_plan_slam.Inverse().R() * normal, plan_point,
            normal};
  }

  std::vector<Eigen::Vector2d> SeenFrom(const Eigen::Vector2d& wearer_plan) const {
    std::vector<Eigen::Vector2d> out;
    for (const Eigen::Vector2d& p : walls_plan)
      if ((p - wearer_plan).norm() < 4.0) out.push_back(truth.Inverse() * p);
    return out;
  }
};

// Drives the estimator along the room's path, an update per second, as the engine does.
void Walk(MclTracker& mcl, const RoomWalk& room, int64_t* t_ns) {
  const std::vector<Eigen::Vector2d> path = {{2, 2}, {2, 5}, {3, 6}, {6, 6}, {8, 5}, {8, 2}};
  for (const Eigen::Vector2d& at : path) {
    *t_ns += 1000000000;
    const Pose2 pose{room.truth.Inverse() * at, 0, 1.6};
    mcl.Correct(pose, *t_ns);
    if (mcl.UpdateDue(*t_ns, 1000)) {
      MclUpdate u = mcl.PrepareUpdate(*t_ns);
      mcl.FinishUpdate(RunMclUpdate(std::move(u), room.SeenFrom(at), *room.index, mcl.options()),
                       *t_ns);
    }
  }
}

// The search that checks a start (a pick, a flip), once an update has weighed it, finds
// only the truth's place.
void CheckStart(MclTracker& mcl, const RoomWalk& room, int64_t t_ns) {
  ASSERT_TRUE(mcl.SearchDue(t_ns, 1000)) << "a start is checked against the whole plan";
  mcl.MarkSearchStarted(t_ns);
  GlobalPlace right;
  right.T_plan_slam = room.truth;
  mcl.OfferPlaces({right}, {}, t_ns);
  EXPECT_FALSE(mcl.SearchDue(t_ns + 10'000'000'000, 1000)) << "once";
}

// Two more walks through the room end on the truth, RELIABLE.
void WalkOntoTheTruth(MclTracker& mcl, const RoomWalk& room, int64_t* t_ns) {
  Walk(mcl, room, t_ns);
  Walk(mcl, room, t_ns);
  EXPECT_THAT(mcl.alignment().T_plan_slam,
              floorpose::testing::IsNearlySe2(room.truth, Deg(0.5), 0.05));
  EXPECT_EQ(mcl.CurrentReliability().flag, ReliabilityFlag::kReliable)
      << mcl.CurrentReliability().reason;
}

// A right pick on the room's inner wall, walked and checked: the belief is sure of its place.
void PickAndCheck(MclTracker& mcl, const RoomWalk& room, int64_t* t_ns) {
  mcl.SetPlan(room.index);
  ASSERT_EQ(mcl.ApplyWallPick(RoomWalk::PickOn(room.truth, {4, 2}), 0), "");
  Walk(mcl, room, t_ns);
  CheckStart(mcl, room, *t_ns);
}

// One update at t_ns on these wall points (slam), run inline.
void UpdateOn(MclTracker& mcl, const ClosestWallIndex& index,
              const std::vector<Eigen::Vector2d>& walls, int64_t t_ns) {
  ASSERT_TRUE(mcl.UpdateDue(t_ns, 1000));
  MclUpdate u = mcl.PrepareUpdate(t_ns);
  ASSERT_TRUE(mcl.FinishUpdate(RunMclUpdate(std::move(u), walls, index, mcl.options()), t_ns));
}

TEST(MclTrackerTest, AWallPickOffByAMetreEndsOnTheTruthAndReliable) {
  RoomWalk room;
  MclTracker mcl({});
  mcl.SetPlan(room.index);
  // A pick on the inner wall, 0.8 m along it and 3 degrees off.
  const Se2 off = Se2{Deg(3), {0, 0.8}} * room.truth;
  const Eigen::Vector2d plan_point{4, 2};
  ASSERT_EQ(mcl.ApplyWallPick(RoomWalk::PickOn(off, plan_point), 0), "");
  EXPECT_NE(mcl.CurrentReliability().flag, ReliabilityFlag::kReliable) << "not yet checked";
  int64_t t = 0;
  Walk(mcl, room, &t);
  EXPECT_THAT(mcl.alignment().T_plan_slam,
              floorpose::testing::IsNearlySe2(room.truth, Deg(0.5), 0.05));
  CheckStart(mcl, room, t);
  Walk(mcl, room, &t);
  const Reliability r = mcl.CurrentReliability();
  EXPECT_EQ(r.flag, ReliabilityFlag::kReliable) << r.reason;
  EXPECT_GT(r.probability, 0.9);
  EXPECT_LE(mcl.belief().size(), 3000u);
}

TEST(MclTrackerTest, APickOnTheWrongWallIsNotReliableAndTheSearchPlacesTheWearer) {
  RoomWalk room;
  MclTracker mcl({});
  mcl.SetPlan(room.index);
  // A pick 4 m and 90 degrees off.
  const Se2 wrong = Se2{Deg(90), {4, 0}} * room.truth;
  const Eigen::Vector2d plan_point{10, 3};
  ASSERT_EQ(mcl.ApplyWallPick(RoomWalk::PickOn(wrong, plan_point), 0), "");
  int64_t t = 0;
  Walk(mcl, room, &t);
  EXPECT_NE(mcl.CurrentReliability().flag, ReliabilityFlag::kReliable);
  EXPECT_TRUE(mcl.SearchDue(t, 1000)) << "the walls do not fit: search the plan";
  // The search finds the truth; the belief takes it as the walk goes on.
  GlobalPlace found;
  found.T_plan_slam = room.truth;
  EXPECT_THAT(mcl.OfferPlaces({found}, {}, t), ::testing::HasSubstr("mixed in"));
  WalkOntoTheTruth(mcl, room, &t);
}

TEST(MclTrackerTest, WithoutAPickTheSearchSeedsTheBelief) {
  RoomWalk room;
  MclTracker mcl({});
  mcl.SetPlan(room.index);
  EXPECT_FALSE(mcl.has_alignment());
  EXPECT_TRUE(mcl.SearchDue(0, 1000));
  GlobalPlace right, twin;
  right.T_plan_slam = room.truth;
  twin.T_plan_slam = Se2{M_PI, {10, 7}} * room.truth;  // the room turned half round
  EXPECT_THAT(mcl.OfferPlaces({twin, right}, {}, 0), ::testing::HasSubstr("seeded with 2"));
  int64_t t = 0;
  WalkOntoTheTruth(mcl, room, &t);
}

// A plain 10 x 7 m room looks the same turned half round its centre: a search's two
// places fit every wall alike, and the belief holds each at about half. Neither is
// published (the poses stay in the SLAM frame, UNRELIABLE) until one is at least
// DEGRADED; a pick is published at once.
TEST(MclTrackerTest, ASearchsPlacesArePublishedOnceOneIsDegraded) {
  const auto parse = MakeFloorPlan(
      "box", {{{0, 0}, {10, 0}}, {{10, 0}, {10, 7}}, {{10, 7}, {0, 7}}, {{0, 7}, {0, 0}}});
  ASSERT_TRUE(parse.ok()) << parse.error;
  const auto index = std::make_shared<ClosestWallIndex>(parse.plan);
  const Se2 truth{Deg(30), {3, -2}};
  std::vector<Eigen::Vector2d> walls_slam;
  for (const Eigen::Vector2d& p : floorpose::testing::SampleWalls(parse.plan, 0.05))
    walls_slam.push_back(truth.Inverse() * p);
  MclTracker mcl({});
  mcl.SetPlan(index);
  int64_t t = 0;
  const Pose2 wearer{truth.Inverse() * Eigen::Vector2d(2, 2), 0, 1.6};
  mcl.Correct(wearer, t);
  GlobalPlace right, turned;
  right.T_plan_slam = truth;
  turned.T_plan_slam = Se2{M_PI, {10, 7}} * truth;
  ASSERT_THAT(mcl.OfferPlaces({right, turned}, walls_slam, t),
              ::testing::HasSubstr("seeded with 2"));
  for (int k = 0; k < 20 && !mcl.has_alignment(); ++k) {
    t += 1000000000;
    const PlanPoseEstimate e = mcl.Correct(wearer, t);
    EXPECT_EQ(e.alignment_version, 0u);
    EXPECT_EQ(e.reliability.flag, ReliabilityFlag::kUnreliable);
    if (k > 0) {
      EXPECT_THAT(e.reliability.reason, ::testing::HasSubstr("none yet at 50%"));
    }
    UpdateOn(mcl, *index, walls_slam, t);
    if (k == 0) {
      // Both places hold about half, and the doubt of a start is still about a half.
      EXPECT_FALSE(mcl.has_alignment()) << "a guess between two places is not published";
      EXPECT_NEAR(mcl.belief().MassWithin(wearer.position, truth * wearer.position, 1.0), 0.5,
                  0.15);
    }
  }
  // Once published (as the walls lower the doubt and the split drifts), at least DEGRADED.
  if (mcl.has_alignment()) {
    EXPECT_GE(mcl.CurrentReliability().probability, 0.5);
  }
  // The wearer picks a wall: that place is published at once.
  ASSERT_EQ(mcl.ApplyWallPick(RoomWalk::PickOn(truth, {10, 3}), t), "");
  EXPECT_TRUE(mcl.has_alignment());
}

// Nine rooms alike to the walls a search ran on, of which the belief takes eight: the
// ninth keeps its part of the belief's mass as "elsewhere" while later walls, which tell
// the eight apart, fit it as they fit the truth. A search that finds no place beyond the
// belief's gives that part back.
TEST(MclTrackerTest, ACrowdLargerThanTheBeliefKeepsItsPlaceInDoubt) {
  std::vector<Segment> segments;
  for (int k = 0; k < 9; ++k) {
    const Eigen::Vector2d o(12.0 * k, 0);
    const Eigen::Vector2d c[] = {o, o + Eigen::Vector2d(6, 0), o + Eigen::Vector2d(6, 4),
                                 o + Eigen::Vector2d(0, 4)};
    for (int i = 0; i < 4; ++i) segments.push_back({c[i], c[(i + 1) % 4]});
    // The truth's room (0) and its twin (8) have a wall in the middle; the rest not.
    if (k == 0 || k == 8)
      segments.push_back({o + Eigen::Vector2d(2, 1), o + Eigen::Vector2d(2, 3)});
  }
  const auto parse = MakeFloorPlan("bays", segments);
  ASSERT_TRUE(parse.ok()) << parse.error;
  const auto index = std::make_shared<ClosestWallIndex>(parse.plan);
  const Se2 truth{Deg(20), {1, -2}};
  std::vector<Eigen::Vector2d> outer_slam, walls_slam;
  for (const Eigen::Vector2d& p : floorpose::testing::SampleWalls(parse.plan, 0.05)) {
    if (p.x() > 6.01) continue;
    walls_slam.push_back(truth.Inverse() * p);
    if (!(std::abs(p.x() - 2) < 1e-6 && p.y() > 0.5 && p.y() < 3.5))
      outer_slam.push_back(truth.Inverse() * p);
  }
  MclTracker mcl({});
  mcl.SetPlan(index);
  int64_t t = 0;
  const Pose2 wearer{truth.Inverse() * Eigen::Vector2d(1.5, 3), 0, 1.6};
  mcl.Correct(wearer, t);
  std::vector<GlobalPlace> crowd(9);
  for (int k = 0; k < 9; ++k) crowd[k].T_plan_slam = Se2{0, {12.0 * k, 0}} * truth;
  ASSERT_THAT(mcl.OfferPlaces(crowd, outer_slam, t), ::testing::HasSubstr("seeded with 8"));
  const auto update = [&] {
    t += 1000000000;
    mcl.Correct(wearer, t);
    UpdateOn(mcl, *index, walls_slam, t);
  };
  // Each update weighs the seconds of walls since the last: a window's worth in 20 s.
  for (int k = 0;
       k < 200 && mcl.belief().MassWithin(wearer.position, truth * wearer.position, 1.0) < 0.97;
       ++k)
    update();
  ASSERT_TRUE(mcl.has_alignment());
  ASSERT_GE(mcl.belief().MassWithin(wearer.position, truth * wearer.position, 1.0), 0.97)
      << "the walls found the truth among the eight";
  const PlanPoseEstimate held = mcl.Correct(wearer, t);
  EXPECT_LT(held.reliability.probability, 1 - 1.0 / 9 + 0.01) << "its twin is one in nine";
  EXPECT_EQ(held.reliability.flag, ReliabilityFlag::kDegraded);
  EXPECT_THAT(held.reliability.reason, ::testing::HasSubstr("more places fit than the belief"));
  // A search finds no place the belief does not hold: the doubt is the walls' again.
  ASSERT_THAT(mcl.OfferPlaces({crowd[0]}, walls_slam, t),
              ::testing::HasSubstr("the belief holds every place found"));
  for (int k = 0; k < 10; ++k) update();
  EXPECT_EQ(mcl.CurrentReliability().flag, ReliabilityFlag::kReliable);
}

// A tracker without a belief, the wearer at plan point `at` at 20 s, seeded by a search
// that found `other` and the truth on `walls`: the belief's mass within 0.7 m of each.
struct Seeded {
  double at_right = 0, at_other = 0;
  bool published = false;  // whether a place is published before new walls weighed them
};
Seeded SeedWithTruthAnd(const RoomWalk& room, const Eigen::Vector2d& at, const GlobalPlace& other,
                        const std::vector<Eigen::Vector2d>& walls) {
  MclTracker mcl({});
  mcl.SetPlan(room.index);
  const int64_t t = 20000000000;
  const Eigen::Vector2d wearer_slam = room.truth.Inverse() * at;
  mcl.Correct({wearer_slam, 0, 1.6}, t);
  GlobalPlace right;
  right.T_plan_slam = room.truth;
  EXPECT_THAT(mcl.OfferPlaces({other, right}, walls, t), ::testing::HasSubstr("seeded with 2"));
  return {mcl.belief().MassWithin(wearer_slam, at, 0.7),
          mcl.belief().MassWithin(wearer_slam, other.T_plan_slam * wearer_slam, 0.7),
          mcl.has_alignment()};
}

TEST(MclTrackerTest, TheSearchsWallsWeighItsPlacesAgainstOneAnother) {
  // Two places found, the truth and one 1.5 m off along the room: the walls the search
  // ran on fit the truth far better, so it starts with nearly all the mass; without them
  // the two start even. Neither is published before new walls weigh them.
  RoomWalk room;
  const Eigen::Vector2d at{2, 2};
  GlobalPlace off;
  off.T_plan_slam = Se2{0, {1.5, 0}} * room.truth;
  std::vector<Eigen::Vector2d> walls = room.SeenFrom(at);
  for (const Eigen::Vector2d& p : room.SeenFrom({8, 5})) walls.push_back(p);
  for (const bool with_walls : {true, false}) {
    SCOPED_TRACE(with_walls ? "with the search's walls" : "without");
    const Seeded seeded =
        SeedWithTruthAnd(room, at, off, with_walls ? walls : std::vector<Eigen::Vector2d>{});
    if (with_walls)
      EXPECT_GT(seeded.at_right, 100 * seeded.at_other);
    else
      EXPECT_NEAR(seeded.at_right, seeded.at_other, 0.1);
    EXPECT_FALSE(seeded.published);
  }
}

TEST(MclTrackerTest, AWalkThroughPlanWallsCostsAPlaceThroughWallPerWall) {
  // Two places that the walls cannot tell apart; under one the wearer's walk before the
  // search went through a plan wall. It starts with through_wall of the other's mass: a
  // price, as for every step after the search, not a veto.
  RoomWalk room;
  GlobalPlace through;
  through.T_plan_slam = Se2{0, {3, 0}} * room.truth;
  through.path_crossings = 1;
  const Seeded seeded = SeedWithTruthAnd(room, {2, 2}, through, {});
  ASSERT_GT(seeded.at_right, 0.5);
  EXPECT_NEAR(seeded.at_other / seeded.at_right, MclOptions{}.motion.through_wall, 0.03);
}

TEST(MclTrackerTest, ASearchThatFindsTheBeliefsOwnPlaceBetterGivesTheOthersLess) {
  // A belief placed by a pick and walked; a search then finds its place and another 1.5 m
  // off, which the search's walls fit far worse. The other gets the doubt's share only when
  // it is all the search found; beside the belief's own place it gets a sliver of it.
  RoomWalk room;
  const Eigen::Vector2d at{8, 5};
  GlobalPlace right, off;
  right.T_plan_slam = room.truth;
  off.T_plan_slam = Se2{0, {1.5, 0}} * room.truth;
  std::vector<Eigen::Vector2d> walls = room.SeenFrom({2, 2});
  for (const Eigen::Vector2d& p : room.SeenFrom(at)) walls.push_back(p);
  std::vector<double> mass_off;
  for (const bool with_right : {false, true}) {
    SCOPED_TRACE(with_right ? "the belief's place found too" : "the other place alone");
    MclTracker mcl({});
    mcl.SetPlan(room.index);
    ASSERT_EQ(mcl.ApplyWallPick(RoomWalk::PickOn(room.truth, {4, 2}), 0), "");
    int64_t t = 0;
    Walk(mcl, room, &t);
    const Eigen::Vector2d wearer_slam = room.truth.Inverse() * at;
    mcl.Correct({wearer_slam, 0, 1.6}, t);
    const std::vector<GlobalPlace> found =
        with_right ? std::vector<GlobalPlace>{right, off} : std::vector<GlobalPlace>{off};
    ASSERT_THAT(mcl.OfferPlaces(found, walls, t), ::testing::HasSubstr("mixed in 1"));
    mass_off.push_back(mcl.belief().MassWithin(wearer_slam, off.T_plan_slam * wearer_slam, 0.7));
  }
  EXPECT_GE(mass_off[0], 0.04) << "at least the offer's 5%";
  EXPECT_LT(mass_off[1], 0.01 * mass_off[0]);
}

TEST(MclTrackerTest, AfterALossOfTrackingTheJumpedFrameIsNotTrustedUntilFoundAgain) {
  RoomWalk room;
  MclTracker mcl({});
  int64_t t = 0;
  PickAndCheck(mcl, room, &t);
  ASSERT_EQ(mcl.CurrentReliability().flag, ReliabilityFlag::kReliable);
  EXPECT_EQ(mcl.frame_since_ns(), INT64_MIN) << "no loss yet: every wall point counts";
  // Five seconds without a pose, then the headset's frame has jumped 1.5 m and 15 degrees
  // about the wearer.
  const Eigen::Vector2d wearer{8, 2};
  room.truth = Se2{0, wearer} * Se2{Deg(15), {1.2, -0.9}} * Se2{0, -wearer} * room.truth;
  t += 5000000000;
  mcl.Correct({room.truth.Inverse() * wearer, 0, 1.6}, t);
  EXPECT_EQ(mcl.frame_since_ns(), t) << "the walls from before are of the old frame";
  EXPECT_EQ(mcl.CurrentReliability().flag, ReliabilityFlag::kUnreliable)
      << "the frame may have jumped: " << mcl.CurrentReliability().reason;
  EXPECT_EQ(mcl.belief().size(), mcl.options().samples.max_samples);
  WalkOntoTheTruth(mcl, room, &t);
}

TEST(MclTrackerTest, AFrameThatJumpedBeyondTheSpreadIsFoundByTheSearchThatChecksIt) {
  RoomWalk room;
  MclTracker mcl({});
  int64_t t = 0;
  PickAndCheck(mcl, room, &t);
  ASSERT_FALSE(mcl.SearchDue(t + 3'000'000'000, 1000)) << "the belief is sure of its place";
  // The headset turned 90 degrees while no pose came: nine times the spread.
  const Eigen::Vector2d wearer{8, 2};
  room.truth = Se2{0, wearer} * Se2{Deg(90), {0.5, 0.5}} * Se2{0, -wearer} * room.truth;
  t += 5000000000;
  mcl.Correct({room.truth.Inverse() * wearer, 0, 1.6}, t);
  EXPECT_FALSE(mcl.SearchDue(t, 1000)) << "not before an update has weighed the new frame";
  UpdateOn(mcl, *room.index, room.SeenFrom(wearer), t);
  ASSERT_TRUE(mcl.SearchDue(t, 1000)) << "the new frame is checked against the whole plan";
  mcl.MarkSearchStarted(t);
  GlobalPlace right;
  right.T_plan_slam = room.truth;
  mcl.OfferPlaces({right}, {}, t);
  WalkOntoTheTruth(mcl, room, &t);
}

// After a loss of tracking the belief is spread by the relocalization model, and a compact
// place a search finds outweighs a spread one of the same fit on its spread alone: the new
// frame is checked once the walls have settled the belief in it.
TEST(MclTrackerTest, ARelocalizedFrameIsCheckedOnceTheWallsHaveSettledTheBelief) {
  RoomWalk room;
  MclTracker mcl({});
  int64_t t = 0;
  PickAndCheck(mcl, room, &t);
  mcl.LoseTracking();
  t += 5000000000;
  mcl.Correct({room.truth.Inverse() * Eigen::Vector2d(8, 2), 0, 1.6}, t);
  // Points far from every plan wall: the update leaves the belief as spread as it was.
  std::vector<Eigen::Vector2d> far;
  for (int i = 0; i < 100; ++i)
    far.push_back(room.truth.Inverse() * Eigen::Vector2d(100 + 0.1 * i, 100));
  UpdateOn(mcl, *room.index, far, t);
  EXPECT_FALSE(mcl.SearchDue(t, 1000)) << "spread by the loss: not yet";
  Walk(mcl, room, &t);
  EXPECT_TRUE(mcl.SearchDue(t, 1000)) << "settled by the walls: checked";
}

TEST(MclTrackerTest, ASearchedPlaceIsNotVouchedForByTheWallsItWasFoundWith) {
  RoomWalk room;
  MclTracker mcl({});
  mcl.SetPlan(room.index);
  int64_t t = 20000000000;
  mcl.Correct({room.truth.Inverse() * Eigen::Vector2d(2, 2), 0, 1.6}, t);
  GlobalPlace right;
  right.T_plan_slam = room.truth;
  ASSERT_THAT(mcl.OfferPlaces({right}, {}, t), ::testing::HasSubstr("seeded with 1"));
  EXPECT_FALSE(mcl.has_alignment()) << "no place to publish before new walls weigh the seed";
  EXPECT_EQ(mcl.Project({Eigen::Vector2d(2, 2), 0, 1.6}).alignment_version, 0u);
  EXPECT_FALSE(mcl.UpdateDue(t, 1000)) << "nothing new since the search";
  t += 1000000000;
  ASSERT_TRUE(mcl.UpdateDue(t, 1000));
  MclUpdate u = mcl.PrepareUpdate(t);
  EXPECT_NEAR(u.evidence, 1.0 / mcl.options().window_s, 1e-9) << "only the walls since the search";
  mcl.FinishUpdate(RunMclUpdate(std::move(u), room.SeenFrom({2, 2}), *room.index, mcl.options()),
                   t);
  EXPECT_TRUE(mcl.has_alignment()) << "weighed: its leading place is published";
  EXPECT_NE(mcl.CurrentReliability().flag, ReliabilityFlag::kReliable)
      << "the best of many places fits the walls it was chosen for, right or not";
  // The walls that come after the search do vouch for it.
  Walk(mcl, room, &t);
  Walk(mcl, room, &t);
  EXPECT_EQ(mcl.CurrentReliability().flag, ReliabilityFlag::kReliable)
      << mcl.CurrentReliability().reason;
}

// One update on a belief whose samples all sit `offset` from the truth, as a walk's price
// for crossing a door drawn closed can pull them.
MclUpdateResult UpdateOffBy(const RoomWalk& room, const Se2& offset) {
  const MclOptions options;
  const Eigen::Vector2d at{2, 5};
  MclUpdate u;
  u.wearer_slam = room.truth.Inverse() * at;
  u.evidence = 1.0 / options.window_s;
  u.mid_fit = Recovery({}, options.measurement, *room.index, 1.0, kPlaceRad).MidFit();
  const Se2 start = Se2{0, at} * offset * Se2{0, -at} * room.truth;
  SplitMix64 rng(6);
  u.belief.AddGaussian(start, PlaceCovariance(0.05, Deg(0.5)), at, 300, 0.0, rng);
  u.belief.Normalize();
  return RunMclUpdate(std::move(u), room.SeenFrom(at), *room.index, options);
}

TEST(MclUpdateTest, ThePlaceIcpReachesOutsideTheBeliefIsOfferedToIt) {
  RoomWalk room;
  const Eigen::Vector2d wearer = room.truth.Inverse() * Eigen::Vector2d(2, 5);
  // 1.2 m off: beyond the leading place's radius, within ICP's correspondence reach.
  const MclUpdateResult off = UpdateOffBy(room, Se2{0, {0, 1.2}});
  ASSERT_TRUE(off.icp.converged);
  EXPECT_LT((off.icp.T_plan_slam * wearer - room.truth * wearer).norm(), 0.1);
  EXPECT_FALSE(off.polished) << "too far to be a polish of the leading place";
  EXPECT_TRUE(off.offered);
  EXPECT_NEAR(off.belief.MassWithin(wearer, room.truth * wearer, 1.0), kOfferShare, 0.005);
  // Near the truth ICP polishes instead, and nothing is offered.
  const MclUpdateResult near = UpdateOffBy(room, Se2{0, {0, 0.3}});
  EXPECT_TRUE(near.polished);
  EXPECT_FALSE(near.offered);
  EXPECT_GT(near.belief.MassWithin(wearer, room.truth * wearer, 1.0), 0.99);
}

TEST(MclUpdateTest, APolishIsNotPublishedWhereItTurnsTheHeadingPastTheBeliefsSpread) {
  RoomWalk room;
  // The belief sure of a heading 5 degrees off (0.5 degrees spread), turned about the
  // wearer: the position there is right, so its mass within 1 m cannot tell, but 5 m
  // along the walk the pose would be 0.4 m off.
  const MclUpdateResult turned = UpdateOffBy(room, Se2{Deg(5), {0, 0}});
  ASSERT_TRUE(turned.icp.converged);
  EXPECT_NEAR(turned.icp.T_plan_slam.theta, room.truth.theta, Deg(0.5)) << "ICP finds it";
  EXPECT_FALSE(turned.polished) << "the belief does not hold that heading";
  EXPECT_FALSE(turned.offered) << "within the place";
  EXPECT_NEAR(turned.published.theta, room.truth.theta + Deg(5), Deg(0.5));
}

// One update that weighs nothing (no new walls) on a belief split between the published
// place, the truth, with `kept` of the mass, and a place 5 m off with the rest, at this
// doubt: which place is published.
Se2 PublishedAfterSplit(const RoomWalk& room, double kept, double elsewhere) {
  const MclOptions options;
  const Eigen::Vector2d at{2, 5};
  MclUpdate u;
  u.wearer_slam = room.truth.Inverse() * at;
  u.elsewhere = elsewhere;
  u.published = room.truth;
  const Se2 other = Se2{0, {0, 5}} * room.truth;
  const Eigen::Matrix3d tight = PlaceCovariance(0.02, Deg(0.2));
  SplitMix64 rng(7);
  u.belief.AddGaussian(room.truth, tight, at, 200, std::log(kept / 200), rng);
  u.belief.AddGaussian(other, tight, other * u.wearer_slam, 200, std::log((1 - kept) / 200), rng);
  return RunMclUpdate(std::move(u), room.SeenFrom(at), *room.index, options).published;
}

TEST(MclUpdateTest, ThePublishedPlaceMovesOnlyToAPlaceTheBeliefTrustsOrFromOneItLeft) {
  RoomWalk room;
  const Eigen::Vector2d wearer = room.truth.Inverse() * Eigen::Vector2d(2, 5);
  const auto off_m = [&](const Se2& T) { return (T * wearer - room.truth * wearer).norm(); };
  EXPECT_LT(off_m(PublishedAfterSplit(room, 0.4, 0.0)), 0.1) << "60% is not twice 40%";
  EXPECT_LT(off_m(PublishedAfterSplit(room, 0.06, 0.5)), 0.1)
      << "94% of the samples, but half the belief is elsewhere: 47% is not to be trusted";
  EXPECT_NEAR(off_m(PublishedAfterSplit(room, 0.06, 0.0)), 5.0, 0.1) << "94%: trusted";
  EXPECT_NEAR(off_m(PublishedAfterSplit(room, 0.02, 0.5)), 5.0, 0.1)
      << "the place in use has lost its samples";
}

}  // namespace
}  // namespace floorpose::tracking
