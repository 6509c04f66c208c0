#include "core/tracking/recovery.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/random.h"

namespace floorpose::tracking {
namespace {

constexpr int kSteps = 2000;  // midpoint rule over [0, reach]

double Logit(double p) { return std::log(p / (1 - p)); }

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

namespace {

// Random points of the plan's bounding box (seeded): the distances of those within the
// index's reach of a wall, and how many were drawn.
struct RandomDraw {
  std::vector<double> distances;
  int drawn = 0;
};

RandomDraw DrawRandomPoints(const ClosestWallIndex& index) {
  const FloorPlan& plan = index.plan();
  SplitMix64 rng(0x72616e64);
  RandomDraw draw;
  for (; draw.drawn < 20 * kSteps && static_cast<int>(draw.distances.size()) < kSteps;
       ++draw.drawn) {
    const Eigen::Vector2d p(rng.Uniform(plan.min.x(), plan.max.x()),
                            rng.Uniform(plan.min.y(), plan.max.y()));
    if (const auto hit = index.Query(p)) draw.distances.push_back(hit->distance);
  }
  return draw;
}

double MeanLogLikelihood(const MeasurementModel& model, const ClosestWallIndex& index,
                         const RandomDraw& draw) {
  const double reach = index.max_distance_m();
  if (draw.distances.empty()) return model.PointLogLikelihood(2 * reach, reach);
  double e = 0;
  for (const double d : draw.distances) e += model.PointLogLikelihood(d, reach);
  return e / static_cast<double>(draw.distances.size());
}

double Places(const ClosestWallIndex& index, const RandomDraw& draw, double place_m,
              double place_rad) {
  const Eigen::Vector2d size = index.plan().max - index.plan().min;
  const double area =
      size.x() * size.y() * static_cast<double>(draw.distances.size()) / std::max(1, draw.drawn);
  const double discs = area / (M_PI * place_m * place_m);
  return std::max(1.0, discs * M_PI / place_rad);
}

}  // namespace

double RandomLogLikelihood(const MeasurementModel& model, const ClosestWallIndex& index) {
  return MeanLogLikelihood(model, index, DrawRandomPoints(index));
}

double PlanPlaces(const ClosestWallIndex& index, double place_m, double place_rad) {
  return Places(index, DrawRandomPoints(index), place_m, place_rad);
}

Recovery::Recovery(const RecoveryOptions& options, const MeasurementModel& model,
                   const ClosestWallIndex& index, double place_m, double place_rad)
    : options_(options), expected_(ExpectedLogLikelihood(model, index.max_distance_m())) {
  const RandomDraw draw = DrawRandomPoints(index);  // one draw for both
  random_ = MeanLogLikelihood(model, index, draw);
  log_places_ = std::log(Places(index, draw, place_m, place_rad));
  Reset();
}

void Recovery::Reset() {
  log_odds_ = right_log_odds_ = unheld_log_odds_ = kNone;
  Doubt(std::clamp(options_.start_doubt, 1e-6, 1 - 1e-6));
  fit_ = expected_;
  fit_sum_ = exponent_sum_ = 0;
  searched_ = relocalized_ = false;
}

void Recovery::Resume(double elsewhere) {
  log_odds_ = Logit(std::clamp(elsewhere, 1e-9, 1 - 1e-9));
  right_log_odds_ = unheld_log_odds_ = kNone;
  fit_ = expected_;
  fit_sum_ = exponent_sum_ = 0;
  searched_ = true;
}

void Recovery::Searched(double unheld) {
  // All but "elsewhere at a random place" is the places that fit: those the belief holds
  // ("here") and those it does not (the search's share of them), here' = (1 - unheld) *
  // (here + right + unheld before).
  unheld = std::clamp(unheld, 0.0, 1 - 1e-9);
  const double fits = 1 + RightOdds() + UnheldOdds();  // in units of "here"
  log_odds_ = std::clamp(log_odds_ - std::log(fits) - std::log1p(-unheld), kNone, -kNone);
  right_log_odds_ = kNone;
  unheld_log_odds_ = unheld > 0 ? std::clamp(Logit(unheld), kNone, -kNone) : kNone;
  searched_ = true;
}

void Recovery::Doubt(double p) {
  // Of the mass "here" gives up, one share in exp(log_places_) fits as a right place.
  const double here = Here();
  const double moved = here * p;
  const double right = here * RightOdds() + moved * std::exp(-log_places_);
  const double random = here * std::exp(log_odds_) + moved * (1 - std::exp(-log_places_));
  log_odds_ = std::clamp(std::log(random / (here - moved)), kNone, -kNone);
  right_log_odds_ = std::clamp(std::log(right / (here - moved)), kNone, -kNone);
  if (unheld_log_odds_ > kNone)  // its odds against the smaller "here"
    unheld_log_odds_ = std::clamp(unheld_log_odds_ - std::log1p(-p), kNone, -kNone);
}

void Recovery::Observe(double mean_log_likelihood, double predictive, double exponent,
                       double dt_s) {
  if (!std::isfinite(mean_log_likelihood) || !std::isfinite(predictive)) return;
  fit_ = mean_log_likelihood;
  // A loss since the last update, then the evidence of this one.
  Doubt(1 - std::exp(-std::max(0.0, dt_s) / options_.lost_s));
  log_odds_ = std::clamp(log_odds_ + exponent * (random_ - mean_log_likelihood), kNone, -kNone);
  // A right place fits as the model expects, or as the walls have fitted since the start
  // where the building is less like its plan; a wrong one as a random place.
  fit_sum_ += exponent * predictive;
  exponent_sum_ += exponent;
  const double right =
      exponent_sum_ > 0 ? std::min(expected_, fit_sum_ / exponent_sum_) : expected_;
  const double mid = 0.5 * (right + random_);
  right_log_odds_ = std::clamp(right_log_odds_ + exponent * (mid - predictive), kNone, -kNone);
}

double Recovery::RightOdds() const {
  return right_log_odds_ > kNone ? std::exp(right_log_odds_) : 0.0;
}

double Recovery::UnheldOdds() const {
  return unheld_log_odds_ > kNone ? std::exp(unheld_log_odds_) : 0.0;
}

double Recovery::Elsewhere() const {
  // The log odds of the three shares of "elsewhere" together, against "here".
  const double log_odds =
      log_odds_ + std::log1p((RightOdds() + UnheldOdds()) * std::exp(-log_odds_));
  return 1 / (1 + std::exp(-log_odds));
}

double Recovery::Here() const { return 1 / (1 + std::exp(log_odds_) + RightOdds() + UnheldOdds()); }

double Recovery::Unheld() const { return UnheldOdds() * Here(); }

bool Recovery::SearchDue(double since_s) const {
  return since_s >= options_.search_interval_s &&
         Elsewhere() * since_s >= options_.search_share * options_.search_interval_s;
}

double Recovery::FitRatio() const { return std::exp(fit_ - expected_); }

}  // namespace floorpose::tracking
