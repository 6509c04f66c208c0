// The reliability model's fit: it recovers a known logistic model from samples drawn
// from it, and the calibration curve bins what it is given.
#include "tools/lib/calibration.h"

#include <gtest/gtest.h>

#include "core/random.h"

namespace floorpose::tools {
namespace {

// Samples with uniform features in [0, 2) and labels drawn from `truth`.
std::vector<CalibrationSample> DrawSamples(const ReliabilityModel& truth, uint64_t seed) {
  SplitMix64 rng(seed);
  std::vector<CalibrationSample> samples;
  for (int i = 0; i < 20000; ++i) {
    CalibrationSample s;
    for (double& f : s.features) f = rng.Uniform(0, 2);
    s.within_1m = rng.Uniform() < truth.Probability(s.features);
    samples.push_back(s);
  }
  return samples;
}

TEST(CalibrationTest, FitRecoversAKnownModel) {
  ReliabilityModel truth;
  truth.bias = 1.0;
  truth.weights = {2.0, -8.0, -1.5, 0.0, 0.0, -0.5, 0.3, -0.4};
  const std::vector<CalibrationSample> samples = DrawSamples(truth, 71);
  const ReliabilityModel fit = FitReliabilityModel(samples, ReliabilityModel{}, 1e-6);
  EXPECT_NEAR(fit.bias, truth.bias, 0.3);
  for (int i = 0; i < ReliabilityModel::kFeatures; ++i)
    EXPECT_NEAR(fit.weights[i], truth.weights[i], 0.25) << ReliabilityFeatures::Name(i);
  // And it is calibrated on its data.
  std::vector<double> p;
  std::vector<bool> y;
  for (const auto& s : samples) {
    p.push_back(fit.Probability(s.features));
    y.push_back(s.within_1m);
  }
  for (const CalibrationBin& b : CalibrationCurve(p, y))
    if (b.n > 500) {
      EXPECT_NEAR(b.observed, b.predicted, 0.05) << b.lo;
    }
}

TEST(CalibrationTest, FitKeepsEachWeightToItsSign) {
  // Data in which heading uncertainty (feature 3) goes with being right: the fit may not
  // reward it, so it holds that weight at 0 and still finds the others.
  ReliabilityModel truth;
  truth.bias = 0.5;
  truth.weights = {2.0, -8.0, -1.5, 1.0, 0.0, 0.0, 0.0, 0.0};
  const std::vector<CalibrationSample> samples = DrawSamples(truth, 72);
  const ReliabilityModel fit = FitReliabilityModel(samples, ReliabilityModel{}, 1e-6);
  for (int i = 0; i < ReliabilityModel::kFeatures; ++i)
    EXPECT_GE(ReliabilityModel::kSigns[i] * fit.weights[i], 0.0) << ReliabilityFeatures::Name(i);
  EXPECT_EQ(fit.weights[3], 0.0);
  EXPECT_NEAR(fit.weights[0], 2.0, 0.3);
  EXPECT_NEAR(fit.weights[1], -8.0, 0.5);
  EXPECT_NEAR(fit.weights[2], -1.5, 0.3);
}

TEST(CalibrationTest, CsvRoundTripsAndRejectsGarbage) {
  CalibrationSample s;
  s.features = {0.9, 0.05, 0.2, 0.4, 0.3, 1.2, 2.0, 0.7};
  s.within_1m = true;
  CalibrationSample back;
  ASSERT_TRUE(ParseCalibrationCsvLine(CalibrationCsvLine(s), &back));
  EXPECT_EQ(back.features, s.features);
  EXPECT_TRUE(back.within_1m);
  EXPECT_FALSE(ParseCalibrationCsvLine("1,2,3", &back));
  EXPECT_FALSE(ParseCalibrationCsvLine("1,2,3,4,5,6,7,8,2", &back));  // label not 0/1
  EXPECT_FALSE(ParseCalibrationCsvLine("1,2,3,4,5,6,7,nan,1", &back));
  EXPECT_FALSE(ParseCalibrationCsvLine("1,2,3,4,5,6,7,8,1,9", &back));
}

TEST(CalibrationTest, CurveBinsByPredictedProbability) {
  const auto bins =
      CalibrationCurve({0.05, 0.07, 0.95, 0.99, 1.0}, {false, true, true, true, false});
  ASSERT_EQ(bins.size(), 10u);
  EXPECT_EQ(bins[0].n, 2u);
  EXPECT_DOUBLE_EQ(bins[0].observed, 0.5);
  EXPECT_EQ(bins[9].n, 3u);
  EXPECT_NEAR(bins[9].observed, 2.0 / 3, 1e-12);
  EXPECT_NE(CalibrationSvg({{"test", bins}}).find("<polyline"), std::string::npos);
}

}  // namespace
}  // namespace floorpose::tools
