// Whether the wearer is at any of the belief's places at all: a filter over four
// hypotheses. "Here": the wearer is at one of the belief's places, and the walls fit as the
// belief says. "Elsewhere" (the belief lost the wearer: a wrong start, a SLAM jump): the
// wearer is at one fixed place the belief does not hold, one of the plan's places (PlanPlaces).
// With the chance of one in that many it is the place the walls fit as a right place does:
// as the model expects (ExpectedLogLikelihood), or as they have fitted since the start
// where that is lower (a building less like its plan fits its right place less well).
// Otherwise it is a place that fits them as a random place of the building does
// (RandomLogLikelihood). Were the wearer elsewhere at a place that fits, the belief's
// places would be wrong ones, which fit the walls as a random place does; here, they fit
// as a right place does. So each update's walls weigh for "elsewhere at a place that
// fits" by how far the belief's fit falls below midway between the two (the log ratio of
// two normals of one spread about them, scaled by the tempering): a near miss that fits
// nearer a random place (a heading wrong after a jump, a look-alike room) is doubted once
// the shortfall outweighs the odds of one place in many, and a right place through
// clutter, which fits nearer a right place's fit, earns the belief. Each update weighs the
// three by the same tempered likelihood the belief uses, after the chance of a loss since
// the last (one per lost_s). A start (pick, place, restore) begins at start_doubt.
//
// The probability of "elsewhere" is published as mass the belief's samples do not hold,
// and while it is high a search of the whole plan reseeds the belief (augmented MCL,
// Probabilistic Robotics table 8.3, with samples drawn from the places the search finds,
// as sensor resetting does, Lenser and Veloso 2000). A search settles the place that fits:
// the places it finds join the belief, and where it finds none there is none, so that
// share of "elsewhere" becomes the belief's. But the search that seeds a belief may find
// more places that fit than the belief takes (a mall's row of shop fronts): those it
// leaves out are a fourth hypothesis, "elsewhere at a look-alike", at their share of the
// search's weight. The walls fit a look-alike as they fit the belief's place, so they
// leave its odds as they are; only the next search, on more walls, settles it.
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
  // A place is a disc of place_m about the wearer and place_rad either side of a heading.
  Recovery(const RecoveryOptions& options, const MeasurementModel& model,
           const ClosestWallIndex& index, double place_m, double place_rad);

  // Starts over at start_doubt (a new pick, place or plan).
  void Reset();
  // A search of the whole plan has been offered to the belief since the start. A wrong
  // start (a pick off by a room) fits its walls better than a random place does, as a
  // right one does: only the other places that fit tell the two apart, so every start is
  // checked by one search. The places it found join the belief: "elsewhere at a place
  // that fits" is the belief's now, but for `unheld`, the share of it at places a seed's
  // search found and the belief did not take (a crowd of look-alikes larger than the
  // belief holds). Walls fit those as they fit the belief's places, so only the next
  // search tells them apart: until then they stay "elsewhere".
  void Searched(double unheld = 0);
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
  // One update: the belief's mean log-likelihood per wall point and its predictive one
  // (BeliefFit), the tempering exponent it was weighed with, dt_s after the last. Each
  // alternative is weighed on the fit its own reference is of: a random place's mean
  // log, and a right place's fit as the belief's, which a spread belief lowers only as
  // much as its places do.
  void Observe(double mean_log_likelihood, double predictive, double exponent, double dt_s);
  // The probability that the wearer is at none of the belief's places...
  double Elsewhere() const;
  // ...and at one a search found that the belief does not hold.
  double Unheld() const;
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
  static constexpr double kNone = -30;  // the log odds of a hypothesis ruled out
  // Moves a share p of "here" to "elsewhere" (a loss, or the doubt of a start).
  void Doubt(double p);
  // The odds of "elsewhere at a place that fits" against "here"; 0 once ruled out.
  double RightOdds() const;
  // ...and of "elsewhere at a place a search found and the belief does not hold".
  double UnheldOdds() const;
  // The probability of "here".
  double Here() const;

  RecoveryOptions options_;
  double expected_ = 0;             // mean log-likelihood per point of a right alignment...
  double random_ = 0;               // ...and of a random one
  double log_places_ = 0;           // log of the plan's distinct places
  double log_odds_ = 0;             // of elsewhere at a random place against here...
  double right_log_odds_ = kNone;   // ...and of elsewhere at a place that fits as a right one
  double unheld_log_odds_ = kNone;  // ...and of elsewhere at a look-alike the belief lacks
  double fit_ = 0;                  // the latest
  double fit_sum_ = 0;              // of the fits since the start, each times its exponent...
  double exponent_sum_ = 0;         // ...and of the exponents
  bool searched_ = false;
  bool relocalized_ = false;
};

// The mean log-likelihood per point the model expects of a right alignment: points at the
// model's own noise about a wall, clutter at its own rate.
double ExpectedLogLikelihood(const MeasurementModel& model, double reach_m);
// ...and of a random one: the mean over random points of the plan within the index's
// reach of a wall (seeded: the same plan gives the same value).
double RandomLogLikelihood(const MeasurementModel& model, const ClosestWallIndex& index);
// How many distinct places the plan holds: its area within the index's reach of a wall, in
// discs of place_m, times the headings in steps of 2 place_rad (at least 1).
double PlanPlaces(const ClosestWallIndex& index, double place_m, double place_rad);

}  // namespace floorpose::tracking
