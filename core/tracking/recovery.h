// Whether the wearer is at any of the belief's places at all: a filter over two
// hypotheses, "here" (the belief) and "elsewhere" (the belief lost the wearer: a wrong
// start, a SLAM jump). Under "elsewhere" the plan is placed at random under the walls, and
// a wall point lies as far from the nearest plan wall as a random point of the building
// does (measured on the plan: RandomLogLikelihood); under "here" it fits as the belief
// says. Each update
// weighs the two by the same tempered likelihood the belief uses, after the chance of a
// loss since the last (one per lost_s). A start (pick, place, restore) begins at
// start_doubt.
//
// The probability of "elsewhere" is published as mass the belief's samples do not hold,
// and while it is high a search of the whole plan reseeds the belief (augmented MCL,
// Probabilistic Robotics table 8.3, with samples drawn from the places the search finds,
// as sensor resetting does, Lenser and Veloso 2000). A building unlike its plan lowers
// the fit of the right place, but not to that of a random one: it is not read as a loss.
#pragma once

#include "core/closest_wall_index.h"
#include "core/tracking/measurement_model.h"

namespace floorpose::tracking {

struct RecoveryOptions {
  double lost_s = 600.0;     // mean time between losses of the wearer, seconds
  double start_doubt = 0.5;  // probability that a pick, place or restore is wrong
  // Search the plan for other places once after every start, then at a rate in proportion
  // to "elsewhere": every search_interval_s at search_share (MclTracker::SearchDue).
  double search_share = 0.2;
  double search_interval_s = 3.0;
};

class Recovery {
 public:
  Recovery() = default;
  Recovery(const RecoveryOptions& options, const MeasurementModel& model,
           const ClosestWallIndex& index);

  // Starts over at start_doubt (a new pick, place or plan).
  void Reset();
  // A search of the whole plan has been offered to the belief since the start. A wrong
  // start (a pick off by a room) fits its walls better than a random place does, as a
  // right one does: only the other places that fit tell the two apart, so every start is
  // checked by one search.
  void Searched() { searched_ = true; }
  // A relocalization starts a new SLAM frame: the belief spreads about where it was, and
  // the start is checked by one search as any other is (a frame that jumped further than
  // the spread fits the walls better than a random place does, too).
  void Relocalized() {
    searched_ = false;
    relocalized_ = true;
  }
  // Since the last start, a relocalization: the belief went on from the old frame, spread
  // by the relocalization model, and is not doubted for it.
  bool relocalized() const { return relocalized_; }
  // Resumes at a saved probability of "elsewhere", the start already checked by a search
  // (a restart of the daemon: the SLAM frame and the wearer went on).
  void Resume(double elsewhere);
  bool searched() const { return searched_; }
  // One update: the belief's mean log-likelihood per wall point, the tempering exponent
  // it was weighed with, dt_s after the last.
  void Observe(double mean_log_likelihood, double exponent, double dt_s);
  // The probability that the wearer is at none of the belief's places.
  double Elsewhere() const;
  // Whether another search of the plan is due since_s after the last: searches come at a
  // rate in proportion to Elsewhere(), every search_interval_s at search_share and ten
  // times as seldom at a tenth of it. The searches cost CPU; the places they find are
  // worth it only as often as the belief may have missed the wearer.
  bool SearchDue(double since_s) const;
  // Halfway between the fit per point of a right alignment and of a random one.
  double MidFit() const { return 0.5 * (expected_ + random_); }
  // The latest fit over the fit expected of a right alignment, as a likelihood ratio per
  // point (1: as expected).
  double FitRatio() const;
  // Whether the latest fit is nearer a right alignment's than a random one's.
  bool Fits() const { return fit_ >= MidFit(); }

 private:
  RecoveryOptions options_;
  double expected_ = 0;  // mean log-likelihood per point of a right alignment...
  double random_ = 0;    // ...and of a random one
  double log_odds_ = 0;  // of elsewhere against here
  double fit_ = 0;       // the latest
  bool searched_ = false;
  bool relocalized_ = false;
};

// The mean log-likelihood per point the model expects of a right alignment: points at the
// model's own noise about a wall, clutter at its own rate.
double ExpectedLogLikelihood(const MeasurementModel& model, double reach_m);
// ...and of a random one: the mean over random points of the plan within the index's
// reach of a wall (seeded: the same plan gives the same value).
double RandomLogLikelihood(const MeasurementModel& model, const ClosestWallIndex& index);

}  // namespace floorpose::tracking
