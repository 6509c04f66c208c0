#include "tools/lib/calibration.h"

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace floorpose::tools {
namespace {

constexpr int kF = ReliabilityModel::kFeatures;

double Sigmoid(double z) { return 1.0 / (1.0 + std::exp(-z)); }

}  // namespace

ReliabilityModel FitReliabilityModel(const std::vector<CalibrationSample>& samples,
                                     const ReliabilityModel& start, double ridge) {
  ReliabilityModel m = start;
  if (samples.empty()) return m;
  using Vec = Eigen::Matrix<double, kF + 1, 1>;
  using Mat = Eigen::Matrix<double, kF + 1, kF + 1>;
  // Standardise the features so that one ridge suits all of them.
  Vec mean = Vec::Zero(), sd = Vec::Ones();
  for (const auto& s : samples)
    for (int i = 0; i < kF; ++i) mean(i + 1) += s.features[i];
  mean /= static_cast<double>(samples.size());
  Vec var = Vec::Zero();
  for (const auto& s : samples)
    for (int i = 0; i < kF; ++i) var(i + 1) += std::pow(s.features[i] - mean(i + 1), 2);
  for (int i = 1; i <= kF; ++i)
    sd(i) = std::max(1e-9, std::sqrt(var(i) / static_cast<double>(samples.size())));
  const double n = static_cast<double>(samples.size());
  Vec w = Vec::Zero();
  for (int iteration = 0; iteration < 50; ++iteration) {
    Mat H = Mat::Zero();
    Vec g = Vec::Zero();
    for (const auto& s : samples) {
      Vec x;
      x(0) = 1.0;
      for (int i = 0; i < kF; ++i) x(i + 1) = (s.features[i] - mean(i + 1)) / sd(i + 1);
      const double p = Sigmoid(w.dot(x));
      g += (p - (s.within_1m ? 1.0 : 0.0)) * x;
      H += std::max(p * (1 - p), 1e-9) * x * x.transpose();
    }
    for (int i = 1; i <= kF; ++i) {  // ridge on the weights, not the bias
      g(i) += ridge * n * w(i);
      H(i, i) += ridge * n;
    }
    // Projected Newton: a weight held at 0 by its sign stays there unless the gradient
    // pulls it the allowed way; the others take the Newton step and are clipped at 0.
    for (int i = 1; i <= kF; ++i) {
      const int sign = ReliabilityModel::kSigns[i - 1];
      if (sign * w(i) > 0 || -sign * g(i) > 0) continue;  // free
      H.row(i).setZero();
      H.col(i).setZero();
      H(i, i) = 1.0;
      g(i) = 0.0;
    }
    const Vec step = H.ldlt().solve(g);
    w -= step;
    for (int i = 1; i <= kF; ++i) {
      const int sign = ReliabilityModel::kSigns[i - 1];
      w(i) = sign * std::max(0.0, sign * w(i));
    }
    if (step.norm() < 1e-8) break;
  }
  // Back to raw features.
  m.bias = w(0);
  for (int i = 0; i < kF; ++i) {
    m.weights[i] = w(i + 1) / sd(i + 1);
    m.bias -= m.weights[i] * mean(i + 1);
  }
  return m;
}

std::vector<CalibrationBin> CalibrationCurve(const std::vector<double>& predicted,
                                             const std::vector<bool>& within_1m) {
  std::vector<CalibrationBin> bins(10);
  for (int b = 0; b < 10; ++b) {
    bins[b].lo = b / 10.0;
    bins[b].hi = (b + 1) / 10.0;
  }
  for (size_t i = 0; i < predicted.size() && i < within_1m.size(); ++i) {
    const int b = std::clamp(static_cast<int>(predicted[i] * 10), 0, 9);
    bins[b].n++;
    bins[b].predicted += predicted[i];
    bins[b].observed += within_1m[i] ? 1.0 : 0.0;
  }
  for (auto& b : bins) {
    if (!b.n) continue;
    b.predicted /= static_cast<double>(b.n);
    b.observed /= static_cast<double>(b.n);
  }
  return bins;
}

std::string CalibrationSvg(
    const std::vector<std::pair<std::string, std::vector<CalibrationBin>>>& curves) {
  const double size = 400, margin = 50;
  auto X = [&](double p) { return margin + p * size; };
  auto Y = [&](double p) { return margin + (1 - p) * size; };
  static const char* const kColours[] = {"#d62728", "#1f77b4", "#2ca02c", "#9467bd"};
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << size + 2 * margin << "\" height=\""
    << size + 2 * margin + 20 * curves.size() << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<rect x=\"" << X(0) << "\" y=\"" << Y(1) << "\" width=\"" << size << "\" height=\"" << size
    << "\" fill=\"none\" stroke=\"black\"/>\n"
    << "<line x1=\"" << X(0) << "\" y1=\"" << Y(0) << "\" x2=\"" << X(1) << "\" y2=\"" << Y(1)
    << "\" stroke=\"#999\" stroke-dasharray=\"4 4\"/>\n";
  for (int t = 0; t <= 10; t += 2) {
    s << "<text x=\"" << X(t / 10.0) - 8 << "\" y=\"" << Y(0) + 16 << "\">" << t / 10.0
      << "</text><text x=\"" << X(0) - 30 << "\" y=\"" << Y(t / 10.0) + 4 << "\">" << t / 10.0
      << "</text>\n";
  }
  s << "<text x=\"" << X(0.3) << "\" y=\"" << Y(0) + 34
    << "\">predicted probability of being within 1 m</text>\n"
    << "<text transform=\"translate(" << X(0) - 38 << "," << Y(0.2)
    << ") rotate(-90)\">observed share within 1 m</text>\n";
  for (size_t c = 0; c < curves.size(); ++c) {
    const char* colour = kColours[c % 4];
    s << "<polyline fill=\"none\" stroke=\"" << colour << "\" stroke-width=\"2\" points=\"";
    for (const auto& b : curves[c].second)
      if (b.n) s << X(b.predicted) << "," << Y(b.observed) << " ";
    s << "\"/>\n";
    for (const auto& b : curves[c].second) {
      if (!b.n) continue;
      // Dot area grows with the number of poses in the bin.
      const double r = 2 + std::min(8.0, std::log10(1.0 + static_cast<double>(b.n)) * 2);
      s << "<circle cx=\"" << X(b.predicted) << "\" cy=\"" << Y(b.observed) << "\" r=\"" << r
        << "\" fill=\"" << colour << "\"/>\n";
    }
    s << "<text x=\"" << X(0) << "\" y=\"" << Y(0) + 54 + 20 * c << "\" fill=\"" << colour << "\">"
      << curves[c].first << "</text>\n";
  }
  s << "</svg>\n";
  return s.str();
}

std::string CalibrationTable(const std::vector<CalibrationBin>& bins) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(2);
  s << "| predicted | poses | mean predicted | observed within 1 m |\n|---|---|---|---|\n";
  for (const auto& b : bins) {
    if (!b.n) continue;
    s << "| " << b.lo << "-" << b.hi << " | " << b.n << " | " << b.predicted << " | " << b.observed
      << " |\n";
  }
  return s.str();
}

std::string CalibrationCsvHeader() {
  std::string h;
  for (int i = 0; i < kF; ++i) h += std::string(ReliabilityFeatures::Name(i)) + ",";
  return h + "within_1m";
}

std::string CalibrationCsvLine(const CalibrationSample& s) {
  std::ostringstream o;
  o.precision(6);
  for (double v : s.features) o << v << ",";
  o << (s.within_1m ? 1 : 0);
  return o.str();
}

bool ParseCalibrationCsvLine(const std::string& line, CalibrationSample* s) {
  std::istringstream in(line);
  std::string cell;
  for (int i = 0; i <= kF; ++i) {
    if (!std::getline(in, cell, ',')) return false;
    char* end = nullptr;
    const double v = std::strtod(cell.c_str(), &end);
    if (end == cell.c_str() || *end != '\0' || !std::isfinite(v)) return false;
    if (i < kF)
      s->features[i] = v;
    else if (v == 0 || v == 1)
      s->within_1m = v == 1;
    else
      return false;
  }
  return !std::getline(in, cell, ',');
}

}  // namespace floorpose::tools
