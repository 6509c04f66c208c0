#include "core/tracking/reliability.h"

#include <cstdio>

namespace floorpose::tracking {

Reliability Assess(const BeliefSummary& s, const PublishOptions& options) {
  Reliability r;
  r.probability = WithinProbability(s.mass_within, s.elsewhere);
  r.flag = r.probability >= options.reliable   ? ReliabilityFlag::kReliable
           : r.probability >= options.degraded ? ReliabilityFlag::kDegraded
                                               : ReliabilityFlag::kUnreliable;
  if (r.flag == ReliabilityFlag::kReliable) return r;
  char text[128];
  if (!s.checked)
    std::snprintf(text, sizeof text, "not yet checked against the walls (%.0f%% within %.0f m)",
                  100 * s.mass_within, options.within_m);
  else if (s.elsewhere >= 1.0 - s.mass_within) {  // the doubt outweighs the spread
    if (!s.fits)
      std::snprintf(text, sizeof text, "the walls fit the plan poorly (%.0f%% of the expected fit)",
                    100 * s.fit_ratio);
    else  // the walls fit: the doubt is the start's, or earlier walls'
      std::snprintf(text, sizeof text, "%s (%.0f%% that the wearer is elsewhere)",
                    !s.searched ? "no search has confirmed the place"
                    : s.crowded ? "more places fit than the belief holds"
                                : "the place is still in doubt",
                    100 * s.elsewhere);
  } else if (s.places > 1)
    std::snprintf(text, sizeof text, "%zu places fit (%.0f%% of the belief here)", s.places,
                  100 * s.mass_within);
  else
    std::snprintf(text, sizeof text, "uncertain: %.0f%% of the belief within %.0f m",
                  100 * s.mass_within, options.within_m);
  r.reason = text;
  return r;
}

}  // namespace floorpose::tracking
