// The published probability is the belief's own: the share of its mass that puts the
// wearer within within_m of the published position, times the probability that the wearer
// is at one of its places at all (Recovery::Elsewhere). The flag is that probability
// against two thresholds; the reason names the term that keeps it down.
#pragma once

#include <string>

#include "core/tracking/alignment.h"

namespace floorpose::tracking {

struct PublishOptions {
  double within_m = 1.0;  // the radius the probability is of, metres (the protocol's 1 m)
  double reliable = 0.9;  // RELIABLE at or above this probability
  double degraded = 0.5;  // DEGRADED at or above this, else UNRELIABLE
};

// What the belief says at a pose.
struct BeliefSummary {
  double mass_within = 0;  // of the samples, within within_m of the published position
  double elsewhere = 0;    // Recovery::Elsewhere
  double fit_ratio = 1;    // Recovery::FitRatio
  bool fits = true;        // the latest walls fit nearer a right place than a random one
  bool searched = true;    // a search of the plan has checked the start (Recovery::searched)
  bool crowded = false;    // ...and most of the doubt is places it found the belief lacks
  size_t places = 1;       // distinct places holding mass (Belief modes)
  bool checked = false;    // an update weighted the belief since it was set
};

// The published probability: mass_within times the probability the wearer is at one of
// the belief's places (1 - elsewhere).
inline double WithinProbability(double mass_within, double elsewhere) {
  return mass_within * (1.0 - elsewhere);
}

Reliability Assess(const BeliefSummary& s, const PublishOptions& options);

}  // namespace floorpose::tracking
