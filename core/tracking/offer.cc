// MclTracker's search side (core/tracking/mcl.h): the places a search of the whole plan
// found, weighed against one another and offered to the belief, as its seed or as
// recovery (augmented MCL).
#include <algorithm>
#include <cmath>

#include "core/thin_cloud.h"
#include "core/tracking/mcl.h"

namespace floorpose::tracking {

std::string MclTracker::OfferPlaces(const std::vector<GlobalPlace>& places,
                                    const std::vector<Eigen::Vector2d>& cloud_slam,
                                    int64_t stamp_ns) {
  double unheld = 0;
  std::string what = MixPlaces(places, cloud_slam, stamp_ns, unheld);
  recovery_.Searched(unheld);
  return what;
}

std::vector<double> MclTracker::PlaceLogWeights(
    const std::vector<const GlobalPlace*>& places,
    const std::vector<Eigen::Vector2d>& cloud_slam) const {
  // The wearer's walk before the search prices each place as the motion model prices
  // every step after it: through_wall for each plan wall walked through.
  std::vector<double> log_weights;
  for (const GlobalPlace* p : places)
    log_weights.push_back(std::log(options_.motion.through_wall) * p->path_crossings);
  const std::vector<Eigen::Vector2d> points = ThinCloud(cloud_slam, 0.1, options_.weigh_points);
  if (!points.empty() && index_) {
    const MeasurementModel& model = options_.measurement;
    const double exponent = std::min(model.independent_points, static_cast<double>(points.size()));
    for (size_t i = 0; i < places.size(); ++i)
      log_weights[i] += exponent * model.MeanLogLikelihood(points, places[i]->T_plan_slam, *index_,
                                                           index_->max_distance_m());
  }
  if (log_weights.empty()) return log_weights;
  const double top = *std::max_element(log_weights.begin(), log_weights.end());
  for (double& w : log_weights) w -= top;
  return log_weights;
}

std::string MclTracker::MixPlaces(const std::vector<GlobalPlace>& places,
                                  const std::vector<Eigen::Vector2d>& cloud_slam, int64_t stamp_ns,
                                  double& unheld) {
  // The places that fit, weighed against one another; the belief takes the first 8.
  std::vector<const GlobalPlace*> fitting;
  for (const GlobalPlace& p : places)
    if (p.rank < 2) fitting.push_back(&p);
  if (fitting.empty()) return "no place fits";
  const size_t k = std::min<size_t>(fitting.size(), 8);
  const Eigen::Vector2d wearer = odometry_.position.value_or(Eigen::Vector2d::Zero());
  const Eigen::Matrix3d P = PlaceCovariance(options_.place_sigma_m, options_.place_sigma_rad);
  if (belief_.empty()) {
    // A seed: the places are the whole belief, and those beyond the 8 keep their part as
    // "elsewhere" (Recovery::Searched).
    const std::vector<double> log_weights = PlaceLogWeights(fitting, cloud_slam);
    const size_t n = std::max<size_t>(1, options_.samples.max_samples / k);
    double all = 0, held = 0;
    for (size_t i = 0; i < fitting.size(); ++i) {
      all += std::exp(log_weights[i]);
      if (i >= k) continue;
      belief_.AddGaussian(fitting[i]->T_plan_slam, P, fitting[i]->T_plan_slam * wearer, n,
                          log_weights[i], rng_);
      held += std::exp(log_weights[i]);
    }
    unheld = 1 - held / all;
    StartBelief(fitting[0]->T_plan_slam, AlignmentSource::kGlobalSearch, stamp_ns);
    // The search's walls weigh its places against one another, not the doubt. Only walls
    // that come after the search weigh the belief against "elsewhere", and until they have
    // there is no place to publish.
    alignment_.version = 0;
    last_update_ns_ = stamp_ns;
    return "seeded with " + std::to_string(k) + " place(s)";
  }
  // Recovery: the places the belief does not hold get the mass the belief may be missing,
  // less what the place it leads with takes of it where the search found that too: the
  // search's walls and the walk weigh the places found against one another. Places beyond
  // the 8 are left to that doubt, which brings the next search: a share of their own would
  // bring it sooner, and every search mixes its look-alikes into a right belief at
  // kOfferShare at least.
  fitting.resize(k);
  const std::vector<double> log_weights = PlaceLogWeights(fitting, cloud_slam);
  const Mode lead = belief_.LeadingMode(wearer, options_.publish.within_m, kPlaceRad);
  std::vector<Se2> fresh;
  std::vector<double> fresh_log_weights;
  double of_taken = 0, of_fresh = 0;
  for (size_t i = 0; i < k; ++i) {
    of_taken += std::exp(log_weights[i]);
    if (SamePlace(fitting[i]->T_plan_slam, lead.T_plan_slam, wearer, options_.publish.within_m,
                  kPlaceRad))
      continue;
    fresh.push_back(fitting[i]->T_plan_slam);
    fresh_log_weights.push_back(log_weights[i]);
    of_fresh += std::exp(log_weights[i]);
  }
  if (fresh.empty()) return "the belief holds every place found";
  const double share = std::max(kOfferShare, recovery_.Elsewhere()) * of_fresh / of_taken;
  belief_.Mix(fresh, fresh_log_weights, P, wearer, share, options_.samples.min_samples / 4, rng_);
  ++belief_version_;  // an update running on the belief without them is void
  return "mixed in " + std::to_string(fresh.size()) + " place(s) at " +
         std::to_string(static_cast<int>(100 * share)) + "%";
}

}  // namespace floorpose::tracking
