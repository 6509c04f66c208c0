#include "tools/lib/calibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace floorpose::tools {
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

}  // namespace floorpose::tools
