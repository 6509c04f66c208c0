// When the walls stop fitting the belief: augmented MCL (Probabilistic Robotics, table
// 8.3). Two running averages of how well the wall points fit the belief, a slow one and a
// fast one; when the fast falls below the slow, the wearer is likely elsewhere, with
// probability 1 - fast / slow. That probability is published as mass the belief's samples
// do not hold, and it draws new samples from the places a search of the whole plan finds
// (sensor resetting, Lenser and Veloso 2000), not from the whole plan at random.
//
// The slow average starts at the fit the measurement model itself expects of a right
// alignment, so a wrong start (a pick on the wrong wall) is seen at its first update, and
// it adapts over slow_s to a building the plan describes worse than the model thinks.
#pragma once

#include "core/tracking/measurement_model.h"

namespace floorpose::tracking {

struct RecoveryOptions {
  double slow_s = 60.0;  // time constant of the slow average, seconds
  double fast_s = 3.0;   // ...of the fast one
  // Search the plan for other places while the probability of being elsewhere is at
  // least this, or the belief is not yet sure of one place; at most every search_interval_s.
  double search_share = 0.2;
  double search_interval_s = 3.0;
};

class Recovery {
 public:
  Recovery() = default;
  Recovery(const RecoveryOptions& options, const MeasurementModel& model, double reach_m);

  // Starts over at the expected fit (a new pick, place or plan).
  void Reset();
  // One update's fit: the belief's mean log-likelihood per wall point, dt_s after the last.
  void Observe(double mean_log_likelihood, double dt_s);
  // The probability that the wearer is at none of the belief's places.
  double Elsewhere() const;
  // The fast average over the expected fit, as a likelihood ratio per point (1: as
  // expected).
  double FitRatio() const;
  bool observed() const { return observed_; }

 private:
  RecoveryOptions options_;
  double expected_ = 0;  // mean log-likelihood per point of a right alignment
  double slow_ = 0, fast_ = 0;
  bool observed_ = false;
};

// The mean log-likelihood per point the model expects of a right alignment: points at the
// model's own noise about a wall, clutter at its own rate.
double ExpectedLogLikelihood(const MeasurementModel& model, double reach_m);

}  // namespace floorpose::tracking
