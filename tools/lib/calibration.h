// How well the published probability of being within 1 m is calibrated: predicted
// against observed, binned, as a curve (SVG) and a table.
#pragma once

#include <string>
#include <vector>

namespace floorpose::tools {

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

}  // namespace floorpose::tools
