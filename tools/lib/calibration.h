// Calibration of the reliability model: a logistic regression of "within 1 m" on the
// tracker's reliability features, fitted on simulated walks, and the curve that shows
// how well a probability is calibrated (predicted against observed).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/tracker.h"

namespace floorpose::tools {

struct CalibrationSample {
  std::array<double, ReliabilityModel::kFeatures> features{};
  bool within_1m = false;
};

// Maximum likelihood with a small ridge on the weights (Newton / IRLS), each weight kept
// to the sign ReliabilityModel::kSigns allows (0 when the data would have it the other
// way); the thresholds are copied from `start`.
ReliabilityModel FitReliabilityModel(const std::vector<CalibrationSample>& samples,
                                     const ReliabilityModel& start, double ridge = 1e-3);

struct CalibrationBin {
  double lo = 0, hi = 0;  // predicted probability range
  size_t n = 0;
  double predicted = 0;  // mean predicted
  double observed = 0;   // share within 1 m
};
// Ten bins of width 0.1 over the predicted probability.
std::vector<CalibrationBin> CalibrationCurve(const std::vector<double>& predicted,
                                             const std::vector<bool>& within_1m);

// Predicted against observed, with the diagonal; one curve per label.
std::string CalibrationSvg(
    const std::vector<std::pair<std::string, std::vector<CalibrationBin>>>& curves);

// The curve as a markdown table.
std::string CalibrationTable(const std::vector<CalibrationBin>& bins);

// CSV of samples: the feature names, then within_1m.
std::string CalibrationCsvHeader();
std::string CalibrationCsvLine(const CalibrationSample& sample);
// Parses what CalibrationCsvLine wrote; false on a malformed line.
bool ParseCalibrationCsvLine(const std::string& line, CalibrationSample* sample);

}  // namespace floorpose::tools
