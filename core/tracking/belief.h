// The belief over the alignment T_plan_slam: weighted samples that can hold several
// places at once (Monte Carlo localization, Probabilistic Robotics chapter 8), resampled
// with KLD-sampling (Fox 2003) so that a belief spread over many places keeps many
// samples and a converged one few.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "core/random.h"
#include "core/se2.h"

namespace floorpose::tracking {

struct Sample {
  Se2 T_plan_slam;
  double log_weight = 0;
};

struct SampleBounds {
  size_t min_samples = 1000;
  size_t max_samples = 3000;
  // KLD-sampling: the error bound and the histogram its count is taken over (the wearer's
  // plan position and heading, at these bins).
  double kld_error = 0.05;  // Fox 2003, a fraction
  double bin_m = 0.5;
  double bin_rad = 10.0 * M_PI / 180;
};

// One place the belief holds: the weighted mean of the samples near its best, and their
// weight.
struct Mode {
  Se2 T_plan_slam;
  double mass = 0;
};

class Belief {
 public:
  bool empty() const { return samples_.empty(); }
  size_t size() const { return samples_.size(); }
  const std::vector<Sample>& samples() const { return samples_; }
  std::vector<Sample>& samples() { return samples_; }
  void Clear() { samples_.clear(); }

  // n samples about T, Gaussian with covariance P of (heading, x, y) about `pivot` (plan).
  void AddGaussian(const Se2& T, const Eigen::Matrix3d& P, const Eigen::Vector2d& pivot, size_t n,
                   double log_weight, SplitMix64& rng);

  // Offers places the belief may have lost: `share` of the mass goes to Gaussians about
  // them (covariance P about the wearer), shared in proportion to exp(log_weights) (one a
  // place), at least min_each samples each; the belief keeps the rest.
  void Mix(const std::vector<Se2>& places, const std::vector<double>& log_weights,
           const Eigen::Matrix3d& P, const Eigen::Vector2d& wearer_slam, double share,
           size_t min_each, SplitMix64& rng);

  // Weights summing to 1 from the log weights (the largest made 0 first).
  std::vector<double> Weights() const;
  // Sets the log weights from normalized weights (after a resample: all equal).
  void Normalize();
  // The effective sample size, 1 / sum w^2, of normalized weights.
  double EffectiveSize() const;

  // Low-variance resampling (Probabilistic Robotics table 4.4) to as many samples as
  // KLD-sampling asks for the histogram of the wearer's plan pose (`wearer_slam` under
  // each sample), within the bounds.
  void Resample(const SampleBounds& bounds, const Eigen::Vector2d& wearer_slam, SplitMix64& rng);

  // n samples drawn by weight (low-variance, as Resample draws), all weighing the same.
  void Draw(size_t n, SplitMix64& rng);

  // The place with the most weight within radius_m (at the wearer) and radius_rad of one
  // of its samples, and the weighted mean of the samples there.
  Mode LeadingMode(const Eigen::Vector2d& wearer_slam, double radius_m, double radius_rad) const;
  // The place that puts the wearer nearest, on average over the belief, to where it puts
  // the wearer: the sample with the least expected distance at the wearer (the estimate
  // that minimizes the expected error), and the weighted mean of the samples within
  // radius_m and radius_rad of it. With one place it is that place; between a spread
  // cloud (a pick's prior) and a tight far place of less weight, it stays in the cloud.
  Mode Estimate(const Eigen::Vector2d& wearer_slam, double radius_m, double radius_rad) const;
  // The same about a given alignment: the weighted mean of the samples near it.
  Mode ModeAt(const Se2& T, const Eigen::Vector2d& wearer_slam, double radius_m,
              double radius_rad) const;
  // The weight of the samples that put the wearer within radius_m of `plan_point`.
  double MassWithin(const Eigen::Vector2d& wearer_slam, const Eigen::Vector2d& plan_point,
                    double radius_m) const;
  // The weighted covariance of (heading, x, y) about `mean` at the wearer.
  Eigen::Matrix3d Covariance(const Se2& mean, const Eigen::Vector2d& wearer_slam) const;
  // ...of the samples within radius_m (at the wearer) and radius_rad of `mean` alone.
  Eigen::Matrix3d CovarianceNear(const Se2& mean, const Eigen::Vector2d& wearer_slam,
                                 double radius_m, double radius_rad) const;

 private:
  // Where each sample puts the wearer on the plan.
  std::vector<Eigen::Vector2d> WearerOnPlan(const Eigen::Vector2d& wearer_slam) const;
  // The samples a place is looked for at: the heaviest and an even spread of the rest.
  std::vector<size_t> Candidates(const std::vector<double>& weights) const;

  std::vector<Sample> samples_;
};

// The covariance of (heading, x, y) of a place known to sigma_rad and sigma_m.
Eigen::Matrix3d PlaceCovariance(double sigma_m, double sigma_rad);

// Whether two alignments put the wearer within radius_m of each other and differ by at
// most radius_rad in heading: one place of the belief.
bool SamePlace(const Se2& a, const Se2& b, const Eigen::Vector2d& wearer_slam, double radius_m,
               double radius_rad);

// KLD-sampling's sample count for k occupied bins (Fox 2003, eq. 12, z for 99%).
size_t KldSamples(size_t bins, double error);

}  // namespace floorpose::tracking
