// `floorpose calibrate`: fits the reliability model (core/tracker.h) on the per-pose
// features an eval-suite run wrote (calibration.csv), prints the coefficients as a
// floorposed configuration snippet, and shows how calibrated the fit is.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <fstream>

#include "tools/floorpose/commands.h"
#include "tools/lib/calibration.h"

namespace floorpose::tools {
namespace {

struct CalibrateOptions {
  std::vector<std::string> data;
  std::string svg;
  double ridge = 1e-3;
};

int RunCalibrate(const CalibrateOptions& o) {
  std::vector<CalibrationSample> samples;
  for (const std::string& path : o.data) {
    std::ifstream in(path);
    if (!in) {
      spdlog::error("{}: cannot open", path);
      return 1;
    }
    std::string line;
    if (!std::getline(in, line) || line != CalibrationCsvHeader()) {
      spdlog::error("{}: not a calibration.csv of this version (header differs)", path);
      return 1;
    }
    size_t number = 1;
    while (std::getline(in, line)) {
      ++number;
      CalibrationSample s;
      if (!ParseCalibrationCsvLine(line, &s)) {
        spdlog::error("{}:{}: malformed line", path, number);
        return 1;
      }
      samples.push_back(s);
    }
  }
  if (samples.size() < 100) {
    spdlog::error("{} samples: too few to fit", samples.size());
    return 1;
  }
  const ReliabilityModel m = FitReliabilityModel(samples, ReliabilityModel{}, o.ridge);
  std::vector<double> predicted;
  std::vector<bool> within;
  size_t reliable = 0, reliable_ok = 0, ok = 0;
  for (const auto& s : samples) {
    const double p = m.Probability(s.features);
    predicted.push_back(p);
    within.push_back(s.within_1m);
    ok += s.within_1m;
    if (p >= m.reliable_probability) {
      ++reliable;
      reliable_ok += s.within_1m;
    }
  }
  std::printf("%zu poses, %.1f%% within 1 m\n", samples.size(), 100.0 * ok / samples.size());
  std::printf("fitted: %.1f%% flagged RELIABLE (p >= %.2f), %.1f%% of those within 1 m\n",
              100.0 * reliable / samples.size(), m.reliable_probability,
              reliable ? 100.0 * reliable_ok / reliable : 0.0);
  const auto curve = CalibrationCurve(predicted, within);
  std::fputs(CalibrationTable(curve).c_str(), stdout);
  std::printf("\nfeatures: bias");
  for (int i = 0; i < ReliabilityModel::kFeatures; ++i)
    std::printf(", %s", ReliabilityFeatures::Name(i));
  std::printf("\ntracking { reliability { coefficients: [%.4g", m.bias);
  for (double w : m.weights) std::printf(", %.4g", w);
  std::printf("] } }\n");
  if (!o.svg.empty())
    std::ofstream(o.svg) << CalibrationSvg({{"fitted model on its training poses", curve}});
  return 0;
}

}  // namespace

Run AddCalibrateCommand(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  app.add_option("--data", o->data, "calibration.csv files written by eval-suite")->required();
  app.add_option("--svg", o->svg, "write the calibration curve of the fit here");
  app.add_option("--ridge", o->ridge, "ridge penalty on the standardised weights")
      ->capture_default_str();
  return [o] { return RunCalibrate(*o); };
}

}  // namespace floorpose::tools
