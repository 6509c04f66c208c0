// RunMclUpdate: one update of the belief, on the worker (core/tracking/mcl.h).
#include <algorithm>
#include <cmath>

#include "core/thin_cloud.h"
#include "core/tracking/mcl.h"

namespace floorpose::tracking {
namespace {

// The published place stays until another holds this many times its mass.
constexpr double kSwitchRatio = 2.0;

// The distinct places holding at least `share` of the belief, heaviest first (at most 4):
// leading modes taken out one after another.
std::vector<Mode> Places(const Belief& belief, const Eigen::Vector2d& wearer_slam, double radius_m,
                         double radius_rad, double share) {
  Belief rest = belief;
  std::vector<Mode> places;
  double left = 1.0;
  for (int i = 0; i < 4 && !rest.empty() && left >= share; ++i) {
    Mode m = rest.LeadingMode(wearer_slam, radius_m, radius_rad);
    m.mass *= left;
    if (m.mass < share) break;
    places.push_back(m);
    left -= m.mass;
    std::vector<Sample>& s = rest.samples();
    s.erase(std::remove_if(s.begin(), s.end(),
                           [&](const Sample& x) {
                             return SamePlace(x.T_plan_slam, m.T_plan_slam, wearer_slam, radius_m,
                                              radius_rad);
                           }),
            s.end());
  }
  return places;
}

// The belief's fit per point to the walls it is weighed on, before weighing.
struct BeliefFit {
  double mean_log = 0;    // the mean over its samples, by prior weight, of their mean logs
  double predictive = 0;  // the log of the weighted mean tempered likelihood, over the exponent
};

// Weighs every sample by the walls new since the last update (the whole window when
// none are marked new), what was in sight and the walk; returns the belief's fit, which
// the recovery filter reads.
BeliefFit WeighSamples(Belief& belief, const MclUpdate& u,
                       const std::vector<Eigen::Vector2d>& cloud,
                       const std::vector<Eigen::Vector2d>& points, double exponent,
                       const ClosestWallIndex& index, const MclOptions& options) {
  const double reach = index.max_distance_m();
  // The fit the recovery filter weighs is predictive: of the walls the belief has not
  // been weighed on yet, under the belief before this update. The walls that shaped the
  // belief fit it well wherever it settled, right or wrong.
  const bool predictive = !u.fresh_slam.empty();
  const std::vector<Eigen::Vector2d> fresh =
      predictive ? ThinCloud(u.fresh_slam, 0.1, options.weigh_points)
                 : std::vector<Eigen::Vector2d>{};
  const std::vector<double> prior = belief.Weights();
  const std::vector<double> nearest = NearestWallPoint(u.sight_slam, cloud);
  // The walls new since the last update weigh the belief, at the window's new share of
  // evidence: a wall counts as it comes in, not spread over the window's length.
  const std::vector<Eigen::Vector2d>& weighed = predictive ? fresh : points;
  BeliefFit fit;
  std::vector<double> terms(belief.size());
  for (size_t i = 0; i < belief.size(); ++i) {
    Sample& s = belief.samples()[i];
    const double mll = options.measurement.MeanLogLikelihood(weighed, s.T_plan_slam, index, reach);
    fit.mean_log += prior[i] * mll;
    terms[i] = std::log(std::max(prior[i], 1e-300)) + exponent * mll;
    const SightFit sight =
        SightLogLikelihood(options.measurement, u.sight_slam, nearest, s.T_plan_slam, index);
    s.log_weight += exponent * (mll + sight.Mean()) +
                    options.motion.PathLogPrior(u.path_slam, s.T_plan_slam, index);
  }
  fit.predictive = fit.mean_log;
  if (exponent > 0 && !terms.empty()) {
    const double top = *std::max_element(terms.begin(), terms.end());
    double sum = 0;
    for (const double t : terms) sum += std::exp(t - top);
    fit.predictive = (top + std::log(sum)) / exponent;
  }
  return fit;
}

// The place with the least expected error at the wearer, or the one published now unless
// another holds kSwitchRatio times its mass and either the belief would trust it (its
// mass, less the doubt, at publish.reliable) or the one in use has lost its samples (less
// than kOfferShare). A belief split between places far apart must not move the published
// pose to one it does not trust: the pose a reader acts on jumps only to a place it may
// act on, or away from one the belief has left.
Mode PublishedMode(const Belief& belief, const MclUpdate& u, const PublishOptions& publish) {
  const Mode best = belief.Estimate(u.wearer_slam, publish.within_m, kPlaceRad);
  if (!u.published) return best;
  const Mode kept = belief.ModeAt(*u.published, u.wearer_slam, publish.within_m, kPlaceRad);
  if (kept.mass * kSwitchRatio >= best.mass) return kept;
  const bool trusted = WithinProbability(best.mass, u.elsewhere) >= publish.reliable;
  return trusted || kept.mass < kOfferShare ? best : kept;
}

// ICP on the whole window from the published place: its polish is published when it stays
// within the place, fits better, and turns the heading no further than the belief holds
// the place's heading (99%, one degree of freedom). The published probability is the
// belief's mass at the wearer, which cannot see a heading's lever arm: a polish turned past
// the belief's spread would carry poses away at a probability that does not describe them.
// The samples stay where the belief put them (moving them with it collapses the belief
// onto whatever ICP settles on, right or not). Beyond the place ICP may reach another,
// within its correspondence reach, that fits the window like a right place and better than the
// published one by more than 1/kOfferShare in the window's likelihood. The belief may have lost its
// samples there (a walk through a door drawn closed is priced, and pulls them to the next opening),
// so the place is offered to the belief as a search's places are; the next updates weigh it.
void PolishOrOffer(MclUpdateResult& out, Belief& belief, const MclUpdate& u,
                   const std::vector<Eigen::Vector2d>& cloud,
                   const std::vector<Eigen::Vector2d>& points, const ClosestWallIndex& index,
                   const MclOptions& options, SplitMix64& rng) {
  const Se2 mode = out.published;
  out.icp = RegisterIcp(cloud, index, mode, options.icp);
  if (!out.icp.converged) return;
  const Eigen::Vector2d pivot = mode * u.wearer_slam;
  const Eigen::Vector3d shift = Difference(out.icp.T_plan_slam, mode, pivot);
  const double moved_m = shift.tail<2>().norm();
  const double reach = index.max_distance_m();
  const double icp_fit =
      options.measurement.MeanLogLikelihood(points, out.icp.T_plan_slam, index, reach);
  const double mode_fit = options.measurement.MeanLogLikelihood(points, mode, index, reach);
  if (moved_m <= options.publish.within_m && std::abs(shift(0)) <= kPlaceRad) {
    constexpr double kChiSquare99OneDof = 6.63;
    const Eigen::Matrix3d spread =
        belief.CovarianceNear(mode, u.wearer_slam, options.publish.within_m, kPlaceRad);
    const bool held =  // a place of one sample has no spread to hold it to
        !(spread(0, 0) > 0) || shift(0) * shift(0) <= kChiSquare99OneDof * spread(0, 0);
    out.polished = held && icp_fit >= mode_fit;
    if (out.polished) out.published = out.icp.T_plan_slam;
    return;
  }
  const bool another_place =
      moved_m <= options.icp.max_correspondence_m && icp_fit > u.mid_fit &&
      options.measurement.independent_points * (icp_fit - mode_fit) > -std::log(kOfferShare);
  if (!another_place) return;
  belief.Mix({out.icp.T_plan_slam}, {0.0},
             PlaceCovariance(options.place_sigma_m, options.place_sigma_rad), u.wearer_slam,
             kOfferShare, options.samples.min_samples / 4, rng);
  out.offered = true;
}

}  // namespace

MclUpdateResult RunMclUpdate(MclUpdate u, const std::vector<Eigen::Vector2d>& cloud,
                             const ClosestWallIndex& index, const MclOptions& options) {
  MclUpdateResult out;
  out.dt_s = u.dt_s;
  out.belief_version = u.belief_version;
  SplitMix64 rng(u.seed);
  Belief& belief = u.belief;
  // Measurement: the window's new share of evidence, and no more than one independent
  // measurement per point of a sparse window.
  const std::vector<Eigen::Vector2d> points = ThinCloud(cloud, 0.1, options.weigh_points);
  out.exponent = u.evidence * std::min(options.measurement.independent_points,
                                       static_cast<double>(points.size()));
  const BeliefFit fit = WeighSamples(belief, u, cloud, points, out.exponent, index, options);
  out.fit = fit.mean_log;
  out.predictive_fit = fit.predictive;
  belief.Normalize();
  if (belief.EffectiveSize() < 0.5 * static_cast<double>(belief.size()) ||
      belief.size() > options.samples.max_samples)
    belief.Resample(options.samples, u.wearer_slam, rng);
  const double radius_m = options.publish.within_m;
  const Mode mode = PublishedMode(belief, u, options.publish);
  out.mode_mass = mode.mass;
  out.published = mode.T_plan_slam;
  PolishOrOffer(out, belief, u, cloud, points, index, options, rng);
  out.places = std::max<size_t>(1, Places(belief, u.wearer_slam, radius_m, kPlaceRad, 0.05).size());
  out.belief = std::move(belief);
  return out;
}

}  // namespace floorpose::tracking
