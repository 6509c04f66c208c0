#include "core/tracking/belief.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>

namespace floorpose::tracking {

namespace {

// Low-variance resampling (Probabilistic Robotics table 4.4): n picks of the normalized
// weights w at one random offset and even steps, each handed to take(index).
template <typename Take>
void DrawLowVariance(const std::vector<double>& w, size_t n, SplitMix64& rng, Take&& take) {
  const double step = 1.0 / static_cast<double>(n);
  double u = rng.Uniform() * step, c = w[0];
  size_t i = 0;
  for (size_t m = 0; m < n; ++m, u += step) {
    while (u > c && i + 1 < w.size()) c += w[++i];
    take(i);
  }
}

}  // namespace

void Belief::AddGaussian(const Se2& T, const Eigen::Matrix3d& P, const Eigen::Vector2d& pivot,
                         size_t n, double log_weight, SplitMix64& rng) {
  Eigen::LLT<Eigen::Matrix3d> llt(P);
  const Eigen::Matrix3d L =
      llt.info() == Eigen::Success ? Eigen::Matrix3d(llt.matrixL()) : Eigen::Matrix3d::Zero();
  samples_.reserve(samples_.size() + n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d z(rng.Gaussian(), rng.Gaussian(), rng.Gaussian());
    // The first sample is the mean itself: a belief of a few samples keeps its centre.
    const Eigen::Vector3d delta = i == 0 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(L * z);
    samples_.push_back({Perturb(T, delta, pivot), log_weight});
  }
}

void Belief::Mix(const std::vector<Se2>& places, const std::vector<double>& log_weights,
                 const Eigen::Matrix3d& P, const Eigen::Vector2d& wearer_slam, double share,
                 size_t min_each, SplitMix64& rng) {
  if (places.empty() || log_weights.size() != places.size()) return;
  Normalize();
  for (Sample& s : samples_) s.log_weight += std::log(1.0 - share);
  const size_t n =
      std::max(min_each, static_cast<size_t>(share * static_cast<double>(size())) / places.size());
  const double top = *std::max_element(log_weights.begin(), log_weights.end());
  double sum = 0;
  for (double w : log_weights) sum += std::exp(w - top);
  for (size_t i = 0; i < places.size(); ++i) {
    const double place_share = share * std::exp(log_weights[i] - top) / sum;
    AddGaussian(places[i], P, places[i] * wearer_slam, n,
                std::log(place_share / static_cast<double>(n)), rng);
  }
  Normalize();
}

std::vector<double> Belief::Weights() const {
  std::vector<double> w(samples_.size());
  double top = -std::numeric_limits<double>::infinity();
  for (const Sample& s : samples_) top = std::max(top, s.log_weight);
  double sum = 0;
  for (size_t i = 0; i < w.size(); ++i) sum += w[i] = std::exp(samples_[i].log_weight - top);
  for (double& x : w) x = sum > 0 ? x / sum : 1.0 / static_cast<double>(w.size());
  return w;
}

void Belief::Normalize() {
  const std::vector<double> w = Weights();
  for (size_t i = 0; i < w.size(); ++i)
    samples_[i].log_weight = w[i] > 0 ? std::log(w[i]) : -std::numeric_limits<double>::infinity();
}

double Belief::EffectiveSize() const {
  double sum2 = 0;
  for (double w : Weights()) sum2 += w * w;
  return sum2 > 0 ? 1.0 / sum2 : 0.0;
}

size_t KldSamples(size_t bins, double error) {
  if (bins <= 1) return 1;
  const double k = static_cast<double>(bins - 1);
  const double z = 2.326;  // upper 1% quantile of the standard normal
  const double a = 2.0 / (9.0 * k);
  const double n = k / (2.0 * error) * std::pow(1.0 - a + std::sqrt(a) * z, 3);
  return static_cast<size_t>(std::ceil(n));
}

void Belief::Resample(const SampleBounds& bounds, const Eigen::Vector2d& wearer_slam,
                      SplitMix64& rng) {
  if (samples_.empty()) return;
  const std::vector<double> w = Weights();
  std::vector<Sample> out;
  out.reserve(bounds.max_samples);
  std::unordered_set<uint64_t> bins;
  auto bin_of = [&](const Se2& T) {
    const Eigen::Vector2d p = T * wearer_slam;
    const auto ix = static_cast<int64_t>(std::floor(p.x() / bounds.bin_m));
    const auto iy = static_cast<int64_t>(std::floor(p.y() / bounds.bin_m));
    const auto ia = static_cast<int64_t>(std::floor((T.theta + M_PI) / bounds.bin_rad));
    return (static_cast<uint64_t>(ix & 0x1fffff) << 42) ^
           (static_cast<uint64_t>(iy & 0x1fffff) << 21) ^ static_cast<uint64_t>(ia & 0x1fffff);
  };
  // Draws in passes of low-variance resampling (one random offset, evenly spaced picks)
  // until the count KLD-sampling asks for the bins filled so far is reached.
  size_t target = bounds.min_samples;
  while (out.size() < std::min(target, bounds.max_samples)) {
    const size_t pass = std::min(target, bounds.max_samples) - out.size();
    DrawLowVariance(w, pass, rng, [&](size_t i) {
      out.push_back({samples_[i].T_plan_slam, 0.0});
      bins.insert(bin_of(samples_[i].T_plan_slam));
    });
    target = std::max(bounds.min_samples, KldSamples(bins.size(), bounds.kld_error));
  }
  const double lw = -std::log(static_cast<double>(out.size()));
  for (Sample& s : out) s.log_weight = lw;
  samples_ = std::move(out);
}

void Belief::Draw(size_t n, SplitMix64& rng) {
  if (samples_.empty() || n == 0) return;
  const std::vector<double> w = Weights();
  std::vector<Sample> out;
  out.reserve(n);
  const double lw = -std::log(static_cast<double>(n));
  DrawLowVariance(w, n, rng, [&](size_t i) { out.push_back({samples_[i].T_plan_slam, lw}); });
  samples_ = std::move(out);
}

bool SamePlace(const Se2& a, const Se2& b, const Eigen::Vector2d& wearer_slam, double radius_m,
               double radius_rad) {
  return (a * wearer_slam - b * wearer_slam).squaredNorm() <= radius_m * radius_m &&
         std::abs(WrapAngle(a.theta - b.theta)) <= radius_rad;
}

Mode Belief::LeadingMode(const Eigen::Vector2d& wearer_slam, double radius_m,
                         double radius_rad) const {
  Mode best;
  if (samples_.empty()) return best;
  const std::vector<double> w = Weights();
  const std::vector<Eigen::Vector2d> at = WearerOnPlan(wearer_slam);
  auto near = [&](size_t i, size_t j) {
    return (at[i] - at[j]).squaredNorm() <= radius_m * radius_m &&
           std::abs(WrapAngle(samples_[i].T_plan_slam.theta - samples_[j].T_plan_slam.theta)) <=
               radius_rad;
  };
  const std::vector<size_t> candidates = Candidates(w);
  size_t centre = candidates[0];
  for (size_t c : candidates) {
    double mass = 0;
    for (size_t j = 0; j < samples_.size(); ++j)
      if (near(c, j)) mass += w[j];
    if (mass > best.mass) {
      best.mass = mass;
      centre = c;
    }
  }
  return ModeAt(samples_[centre].T_plan_slam, wearer_slam, radius_m, radius_rad);
}

std::vector<Eigen::Vector2d> Belief::WearerOnPlan(const Eigen::Vector2d& wearer_slam) const {
  std::vector<Eigen::Vector2d> at(samples_.size());
  for (size_t i = 0; i < at.size(); ++i) at[i] = samples_[i].T_plan_slam * wearer_slam;
  return at;
}

std::vector<size_t> Belief::Candidates(const std::vector<double>& w) const {
  // At most 64: the 32 heaviest and 32 spread evenly over the rest.
  std::vector<size_t> order(samples_.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  const size_t heavy = std::min<size_t>(32, order.size());
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(heavy), order.end(),
                    [&](size_t a, size_t b) { return w[a] > w[b]; });
  std::vector<size_t> candidates(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(heavy));
  const size_t stride = std::max<size_t>(1, samples_.size() / 32);
  for (size_t i = 0; i < samples_.size(); i += stride) candidates.push_back(i);
  return candidates;
}

Mode Belief::Estimate(const Eigen::Vector2d& wearer_slam, double radius_m,
                      double radius_rad) const {
  if (samples_.empty()) return {};
  const std::vector<double> w = Weights();
  const std::vector<Eigen::Vector2d> at = WearerOnPlan(wearer_slam);
  size_t centre = 0;
  double least = std::numeric_limits<double>::infinity();
  for (size_t c : Candidates(w)) {
    double expected = 0;
    for (size_t j = 0; j < samples_.size(); ++j) expected += w[j] * (at[j] - at[c]).norm();
    if (expected < least) {
      least = expected;
      centre = c;
    }
  }
  return ModeAt(samples_[centre].T_plan_slam, wearer_slam, radius_m, radius_rad);
}

Mode Belief::ModeAt(const Se2& T0, const Eigen::Vector2d& wearer_slam, double radius_m,
                    double radius_rad) const {
  // The weighted mean about T0, as a perturbation at the wearer.
  const std::vector<double> w = Weights();
  const Eigen::Vector2d pivot = T0 * wearer_slam;
  Mode mode;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (size_t j = 0; j < samples_.size(); ++j) {
    const Eigen::Vector3d d = Difference(samples_[j].T_plan_slam, T0, pivot);
    if (d.tail<2>().squaredNorm() > radius_m * radius_m || std::abs(d(0)) > radius_rad) continue;
    mean += w[j] * d;
    mode.mass += w[j];
  }
  mode.T_plan_slam = mode.mass > 0 ? Perturb(T0, mean / mode.mass, pivot) : T0;
  return mode;
}

double Belief::MassWithin(const Eigen::Vector2d& wearer_slam, const Eigen::Vector2d& plan_point,
                          double radius_m) const {
  const std::vector<double> w = Weights();
  double mass = 0;
  for (size_t i = 0; i < w.size(); ++i)
    if ((samples_[i].T_plan_slam * wearer_slam - plan_point).squaredNorm() <= radius_m * radius_m)
      mass += w[i];
  return mass;
}

Eigen::Matrix3d Belief::Covariance(const Se2& mean, const Eigen::Vector2d& wearer_slam) const {
  const std::vector<double> w = Weights();
  const Eigen::Vector2d pivot = mean * wearer_slam;
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < w.size(); ++i) {
    const Eigen::Vector3d d = Difference(samples_[i].T_plan_slam, mean, pivot);
    C += w[i] * d * d.transpose();
  }
  return C;
}

Eigen::Matrix3d Belief::CovarianceNear(const Se2& mean, const Eigen::Vector2d& wearer_slam,
                                       double radius_m, double radius_rad) const {
  const std::vector<double> w = Weights();
  const Eigen::Vector2d pivot = mean * wearer_slam;
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  double near = 0;
  for (size_t i = 0; i < w.size(); ++i) {
    if (!SamePlace(samples_[i].T_plan_slam, mean, wearer_slam, radius_m, radius_rad)) continue;
    const Eigen::Vector3d d = Difference(samples_[i].T_plan_slam, mean, pivot);
    C += w[i] * d * d.transpose();
    near += w[i];
  }
  return near > 0 ? Eigen::Matrix3d(C / near) : C;
}

Eigen::Matrix3d PlaceCovariance(double sigma_m, double sigma_rad) {
  return Eigen::Vector3d(sigma_rad * sigma_rad, sigma_m * sigma_m, sigma_m * sigma_m).asDiagonal();
}

}  // namespace floorpose::tracking
