// eval-compare's paired bootstrap (tools/lib/compare.h) on runs made here: a change of
// one walk stays within noise, a change of every walk does not.
#include "tools/lib/compare.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/random.h"

namespace floorpose::tools {
namespace {

std::vector<RunFigures> Runs(int n, uint64_t seed) {
  SplitMix64 rng(seed);
  std::vector<RunFigures> runs;
  for (int i = 0; i < n; ++i) {
    RunFigures r;
    r.key = "mcl plan" + std::to_string(i % 9) + " s" + std::to_string(i);
    r.mean_error_m = rng.Uniform(0.1, 0.5);
    r.max_error_m = rng.Uniform(0.5, 3.0);
    r.scored_poses = 500;
    r.reliable_poses = 400;
    r.false_poses = rng.Uniform() < 0.1 ? rng.Uniform(0, 100) : 0;
    runs.push_back(r);
  }
  return runs;
}

Difference Row(const std::vector<Difference>& d, const std::string& name) {
  for (const Difference& x : d)
    if (name == x.name) return x;
  ADD_FAILURE() << "no row " << name;
  return d.front();
}

TEST(CompareTest, OneWalkIsWithinNoiseAndEveryWalkIsNot) {
  const std::vector<RunFigures> base = Runs(243, 1);
  const auto same = Compare(base, base, 500, 7);
  for (const Difference& d : same) {
    EXPECT_EQ(d.base, d.next) << d.name;
    EXPECT_EQ(d.low, 0.0) << d.name;
    EXPECT_EQ(d.high, 0.0) << d.name;
  }
  // One walk 200 poses more RELIABLE off: the interval of false poses spans 0.
  std::vector<RunFigures> one = base;
  one[5].false_poses += 200;
  const std::vector<Difference> d1 = Compare(base, one, 2000, 7);
  const Difference f1 = Row(d1, "RELIABLE more than 1 m off");
  EXPECT_EQ(f1.next - f1.base, 200);
  EXPECT_LE(f1.low, 0.0);
  EXPECT_GT(f1.high, 0.0);
  // Every walk 0.05 m worse: the interval of the mean error is above 0.
  std::vector<RunFigures> all = base;
  for (RunFigures& r : all) r.mean_error_m += 0.05;
  const std::vector<Difference> d2 = Compare(base, all, 2000, 7);
  const Difference m = Row(d2, "mean error, m");
  EXPECT_NEAR(m.next - m.base, 0.05, 1e-12);
  EXPECT_NEAR(m.low, 0.05, 1e-9);
  EXPECT_NEAR(m.high, 0.05, 1e-9);
}

TEST(CompareTest, TheBrierScoreIsPooledOverPoses) {
  RunFigures a, b;
  a.key = "mcl p office 1";
  a.scored_poses = 100;
  a.brier = 0.01;
  b.key = "mcl p hall 1";
  b.scored_poses = 300;
  b.brier = 0.05;
  const SuiteFigures f = Figures({&a, &b});
  EXPECT_NEAR(f.brier, (100 * 0.01 + 300 * 0.05) / 400, 1e-12) << "weighed by poses, not runs";
  std::vector<RunFigures> next = {a, b};
  next[1].brier = 0.03;
  const Difference d = Row(Compare({a, b}, next, 200, 7), "Brier score of the probability");
  EXPECT_NEAR(d.next - d.base, 300 * -0.02 / 400, 1e-12);
}

TEST(CompareTest, RunsAreCountedByWhenTheyAreFirstReliableWithinAMetre) {
  std::vector<RunFigures> base(4);
  const double seconds[] = {12.0, 30.0, 31.0, -1.0};  // -1: never
  for (size_t i = 0; i < base.size(); ++i) {
    base[i].key = "mcl p office " + std::to_string(i);
    base[i].time_to_recovered_s = seconds[i];
  }
  std::vector<const RunFigures*> all;
  for (const RunFigures& r : base) all.push_back(&r);
  const SuiteFigures f = Figures(all);
  EXPECT_DOUBLE_EQ(f.recovered, 0.5) << "12 s and 30 s: within 30 s";
  EXPECT_EQ(f.never_recovered, 1);
  // The slow run back in 20 s, the lost one in 40 s: one more by 30 s, none never.
  std::vector<RunFigures> next = base;
  next[2].time_to_recovered_s = 20.0;
  next[3].time_to_recovered_s = 40.0;
  const std::vector<Difference> d = Compare(base, next, 500, 7);
  EXPECT_DOUBLE_EQ(Row(d, "runs RELIABLE within 1 m 30 s after the first alignment").next, 0.75);
  EXPECT_EQ(Row(d, "runs never RELIABLE within 1 m").next, 0);
}

TEST(CompareTest, RunsArePairedByWalkAndBadLinesAreRefused) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "compare";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "a.json")
      << R"({"method":"mcl","plan":"p","scenario":"office","seed":1,"poses":100,)"
      << R"("reliable_fraction":0.5,"false_reliable_poses":5,"mean_error_m":0.2,"max_error_m":6,)"
      << R"("brier":0.04,"time_to_recovered_s":7.5})"
      << "\n\n"
      << R"({"method":"mcl","plan":"p","scenario":"hall","seed":1,"poses":100,)"
      << R"("reliable_fraction":0.8,"false_reliable_poses":0,"mean_error_m":0.4,"max_error_m":1})"
      << "\n";
  std::ofstream(dir / "bad.json") << "{\"method\": \"mcl\"}\n";
  std::vector<RunFigures> a, bad;
  ASSERT_EQ(ReadRuns((dir / "a.json").string(), &a), "");
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0].reliable_poses, 50);
  EXPECT_EQ(a[0].brier, 0.04);
  EXPECT_EQ(a[1].brier, 0.0) << "results.json of before the score: none";
  EXPECT_EQ(a[0].time_to_recovered_s, 7.5);
  EXPECT_LT(a[1].time_to_recovered_s, 0) << "none written: never";
  EXPECT_NE(ReadRuns((dir / "bad.json").string(), &bad), "");
  EXPECT_NE(ReadRuns((dir / "missing.json").string(), &bad), "");
  // Only the walk in both counts: the office run.
  const std::vector<RunFigures> office = {a[0]};
  const auto d = Compare(a, office, 200, 3);
  EXPECT_EQ(Row(d, "runs more than 5 m off").base, 1);
  EXPECT_DOUBLE_EQ(Row(d, "RELIABLE within 1 m").base, 0.9);
  EXPECT_DOUBLE_EQ(Row(d, "mean error, m").base, 0.2);
}

}  // namespace
}  // namespace floorpose::tools
