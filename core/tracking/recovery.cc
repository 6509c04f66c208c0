#include "core/tracking/recovery.h"

#include <algorithm>
#include <cmath>

namespace floorpose::tracking {

double ExpectedLogLikelihood(const MeasurementModel& model, double reach_m) {
  // E[log p(d)] by the midpoint rule over [0, reach]: hits half-normal, clutter uniform.
  const int n = 2000;
  const double step = reach_m / n;
  double e = 0;
  for (int i = 0; i < n; ++i) {
    const double d = (i + 0.5) * step;
    const double hit = std::sqrt(2.0 / M_PI) / model.sigma_m *
                       std::exp(-0.5 * d * d / (model.sigma_m * model.sigma_m));
    const double density = (1 - model.clutter) * hit + model.clutter / reach_m;
    e += density * model.PointLogLikelihood(d, reach_m) * step;
  }
  return e;
}

Recovery::Recovery(const RecoveryOptions& options, const MeasurementModel& model, double reach_m)
    : options_(options), expected_(ExpectedLogLikelihood(model, reach_m)) {
  Reset();
}

void Recovery::Reset() {
  slow_ = fast_ = expected_;
  observed_ = false;
}

void Recovery::Observe(double mean_log_likelihood, double dt_s) {
  if (!std::isfinite(mean_log_likelihood)) return;
  const double dt = std::max(0.0, dt_s);
  // The slow average never rises above the expected fit: a place fitting better than the
  // model expects does not make an ordinary fit look like a loss.
  slow_ += std::min(1.0, dt / options_.slow_s) * (mean_log_likelihood - slow_);
  slow_ = std::min(slow_, expected_);
  // The first fit after a start is taken whole: a wrong start shows at once.
  fast_ += (observed_ ? std::min(1.0, dt / options_.fast_s) : 1.0) * (mean_log_likelihood - fast_);
  observed_ = true;
}

double Recovery::FitRatio() const { return std::exp(fast_ - expected_); }

double Recovery::Elsewhere() const {
  // Likelihoods per point: exp of the averages of log-likelihoods.
  return std::clamp(1.0 - std::exp(fast_ - slow_), 0.0, 1.0);
}

}  // namespace floorpose::tracking
