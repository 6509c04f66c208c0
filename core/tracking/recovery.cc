#include "core/tracking/recovery.h"

#include <algorithm>
#include <cmath>

#include "core/random.h"

namespace floorpose::tracking {
namespace {

constexpr int kSteps = 2000;  // midpoint rule over [0, reach]

double Logit(double p) { return std::log(p / (1 - p)); }
double Logistic(double x) { return 1 / (1 + std::exp(-x)); }

}  // namespace

double ExpectedLogLikelihood(const MeasurementModel& model, double reach_m) {
  const double step = reach_m / kSteps;
  double e = 0;
  for (int i = 0; i < kSteps; ++i) {
    const double d = (i + 0.5) * step;
    const double density = (1 - model.clutter) * model.HitDensity(d) + model.clutter / reach_m;
    e += density * model.PointLogLikelihood(d, reach_m) * step;
  }
  return e;
}

double RandomLogLikelihood(const MeasurementModel& model, const ClosestWallIndex& index) {
  const FloorPlan& plan = index.plan();
  const double reach = index.max_distance_m();
  SplitMix64 rng(0x72616e64);
  double e = 0;
  int n = 0;
  for (int i = 0; i < 20 * kSteps && n < kSteps; ++i) {
    const Eigen::Vector2d p(rng.Uniform(plan.min.x(), plan.max.x()),
                            rng.Uniform(plan.min.y(), plan.max.y()));
    if (const auto hit = index.Query(p)) {
      e += model.PointLogLikelihood(hit->distance, reach);
      ++n;
    }
  }
  return n > 0 ? e / n : model.PointLogLikelihood(2 * reach, reach);
}

Recovery::Recovery(const RecoveryOptions& options, const MeasurementModel& model,
                   const ClosestWallIndex& index)
    : options_(options),
      expected_(ExpectedLogLikelihood(model, index.max_distance_m())),
      random_(RandomLogLikelihood(model, index)) {
  Reset();
}

void Recovery::Reset() {
  log_odds_ = Logit(std::clamp(options_.start_doubt, 1e-6, 1 - 1e-6));
  fit_ = expected_;
  searched_ = relocalized_ = false;
}

void Recovery::Resume(double elsewhere) {
  log_odds_ = Logit(std::clamp(elsewhere, 1e-9, 1 - 1e-9));
  fit_ = expected_;
  searched_ = true;
}

void Recovery::Observe(double mean_log_likelihood, double exponent, double dt_s) {
  if (!std::isfinite(mean_log_likelihood)) return;
  fit_ = mean_log_likelihood;
  // A loss since the last update, then the evidence of this one.
  double p = Logistic(log_odds_);
  p += (1 - p) * (1 - std::exp(-std::max(0.0, dt_s) / options_.lost_s));
  log_odds_ = Logit(std::clamp(p, 1e-9, 1 - 1e-9)) + exponent * (random_ - mean_log_likelihood);
  log_odds_ = std::clamp(log_odds_, -30.0, 30.0);
}

double Recovery::Elsewhere() const { return Logistic(log_odds_); }

bool Recovery::SearchDue(double since_s) const {
  return since_s >= options_.search_interval_s &&
         Elsewhere() * since_s >= options_.search_share * options_.search_interval_s;
}

double Recovery::FitRatio() const { return std::exp(fit_ - expected_); }

}  // namespace floorpose::tracking
