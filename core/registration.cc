#include "core/registration.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "core/select.h"
#include "core/thin_cloud.h"

namespace floorpose {

const char* ToString(RegistrationMethod method) {
  switch (method) {
    case RegistrationMethod::kIcp: return "icp";
    case RegistrationMethod::kIk: return "ik";
    case RegistrationMethod::kHough: return "hough";
  }
  return "?";
}

bool ParseRegistrationMethod(const std::string& name, RegistrationMethod* method) {
  for (RegistrationMethod m :
       {RegistrationMethod::kIcp, RegistrationMethod::kIk, RegistrationMethod::kHough}) {
    if (name == ToString(m)) {
      *method = m;
      return true;
    }
  }
  return false;
}

void EvaluateFit(const std::vector<Eigen::Vector2d>& points, const ClosestWallIndex& index,
                 const Se2& T, double max_corr, double inlier_threshold, RegistrationResult* result,
                 double* truncated_mse) {
  const Eigen::Matrix2d R = T.R();
  double sum_matched = 0, sum_inlier = 0, sum_trunc = 0;
  uint32_t matched = 0, inliers = 0;
  const double cap2 = max_corr * max_corr;
  for (const Eigen::Vector2d& p : points) {
    const auto hit = index.Query(R * p + T.t);
    if (!hit || hit->distance > max_corr) {
      sum_trunc += cap2;
      continue;
    }
    const double d2 = hit->distance * hit->distance;
    sum_trunc += d2;
    sum_matched += d2;
    ++matched;
    if (hit->distance <= inlier_threshold) {
      sum_inlier += d2;
      ++inliers;
    }
  }
  if (result) {
    result->points = static_cast<uint32_t>(points.size());
    result->matched = matched;
    result->inliers = inliers;
    result->rmse = matched ? std::sqrt(sum_matched / matched) : 0.0;
    result->inlier_rmse = inliers ? std::sqrt(sum_inlier / inliers) : 0.0;
  }
  if (truncated_mse) *truncated_mse = points.empty() ? cap2 : sum_trunc / points.size();
}

namespace {

// One constraint row: a . (theta, x, y) + r = 0 in the linearisation (eq. 4.4).
struct Row {
  Eigen::Vector2d p;  // transformed point
  Eigen::Vector2d n;  // direction of the residual (a wall normal, or an axis)
  double r;           // signed residual n . (p - y)
  double d;           // distance to the closest point on the segment
  double w = 1;       // how many of the cloud's points it stands for (a voxel's)
};

constexpr double kFreeEndM = 0.1;  // see MakeRows

// The closest-wall pairs of a pass, with their weighed sums (KeepPairs' rejection).
struct Pairs {
  std::vector<Row> rows;
  double weight = 0;      // sum of w
  double weighed_d2 = 0;  // sum of w d^2
};

// Closest-wall pairs of the transformed points (every stride-th), within max_corr, each
// weighing its count of the cloud's points (1 without counts). With
// point_to_point_at_ends, a closest point at a segment's end gives two rows (x and y), as
// the squared distance to a point is isotropic there (Pottmann et al. 2004, section 3).
void MakeRows(const std::vector<Eigen::Vector2d>& points, const std::vector<uint32_t>* counts,
              size_t stride, const Se2& T, const ClosestWallIndex& index, double max_corr,
              bool point_to_point_at_ends, Pairs* pairs) {
  std::vector<Row>& rows = pairs->rows;
  rows.clear();
  double weight = 0, weighed_d2 = 0;
  // Each row adds to the sums as it is written (w d^2 for the rejection's RMS).
  auto add = [&](const Row& row) {
    rows.push_back(row);
    weight += row.w;
    weighed_d2 += row.w * row.d * row.d;
  };
  const Eigen::Matrix2d R = T.R();
  const auto& segments = index.plan().segments;
  for (size_t i = 0; i < points.size(); i += stride) {
    const Eigen::Vector2d p = R * points[i] + T.t;
    const auto hit = index.Query(p);
    if (!hit || hit->distance > max_corr) continue;
    const Segment& s = segments[hit->segment];
    // Only well beyond a free end: points in the joint between two collinear pieces of
    // a wall (digitised plans are full of them) still see a line, not a corner.
    bool at_end = false;
    if (point_to_point_at_ends && hit->distance > 1e-9) {
      const Eigen::Vector2d d = s.b - s.a;
      const double len = d.norm();
      const double along = (p - s.a).dot(d) / len;  // metres from a towards b
      at_end = along < -kFreeEndM || along > len + kFreeEndM;
    }
    const double w = counts ? (*counts)[i] : 1.0;
    if (at_end) {
      const Eigen::Vector2d e = p - hit->point;
      add({p, Eigen::Vector2d::UnitX(), e.x(), hit->distance, w});
      add({p, Eigen::Vector2d::UnitY(), e.y(), hit->distance, w});
    } else {
      add({p, hit->normal, hit->normal.dot(p - hit->point), hit->distance, w});
    }
  }
  pairs->weight = weight;
  pairs->weighed_d2 = weighed_d2;
}

struct Step {
  bool ok = false;
  std::string reason;
  Eigen::Vector3d delta = Eigen::Vector3d::Zero();  // (theta, x, y) about the centroid
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();  // unscaled normal matrix
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();
  Eigen::Matrix3d eigenvectors = Eigen::Matrix3d::Identity();
  std::vector<Eigen::Vector3d> degenerate;
  // The standard deviations of the fit's translation (both axes together, metres) and
  // rotation (radians) in its points' noise: Cov = s^2 H^-1, s^2 the weighed squared
  // residuals per kept pair. Infinite when a direction is unconstrained.
  double noise_translation_m = std::numeric_limits<double>::infinity();
  double noise_rotation_rad = std::numeric_limits<double>::infinity();
};

// The pairs a step weighs: picky ICP (Zinsser et al. 2003) keeps those within
// reject_sigma deviations, about their centroid, with the Cauchy scale and RMS radius
// they give. Fewer than 3 kept: count says so, and the scales are not set.
struct KeptPairs {
  double reject = 0;  // a pair at most this far apart is kept, metres
  double cauchy = 0;  // the Cauchy scale: the median absolute residual times the factor
  double radius = 0;  // RMS distance of the kept points from their centroid (at least 0.1 m)
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  size_t count = 0;
};

KeptPairs KeepPairs(const Pairs& pairs, const IcpOptions& o) {
  KeptPairs k;
  k.reject = std::max(o.reject_sigma * std::sqrt(pairs.weighed_d2 / pairs.weight), 0.01);
  // The Cauchy scale, where the kernel is on, is the median absolute residual of the kept
  // pairs (of the rows, not weighed by their counts).
  const bool cauchy = o.cauchy_scale_factor > 0;
  thread_local std::vector<double> abs_r;
  abs_r.clear();
  double kept_weight = 0;
  for (const Row& q : pairs.rows) {
    if (q.d > k.reject) continue;
    ++k.count;
    if (cauchy) abs_r.push_back(std::abs(q.r));
    k.centroid += q.w * q.p;
    kept_weight += q.w;
  }
  if (k.count < 3) return k;
  k.centroid /= kept_weight;
  if (cauchy)
    k.cauchy = std::max(o.cauchy_scale_factor * NthSmallest(abs_r, abs_r.size() / 2), 0.01);
  double radius2 = 0;
  for (const Row& q : pairs.rows)
    if (q.d <= k.reject) radius2 += q.w * (q.p - k.centroid).squaredNorm();
  k.radius = std::max(std::sqrt(radius2 / kept_weight), 0.1);
  return k;
}

// Picky rejection, Cauchy weights, and the weighted least-squares step with solution
// remapping. Unknowns are (theta, x, y) about the centroid of the rows; theta is scaled
// by the RMS radius so that its eigenvalue compares with the translations'.
Step SolveStep(const Pairs& pairs, const IcpOptions& o, bool translation_only) {
  const std::vector<Row>& rows = pairs.rows;
  Step st;
  if (rows.size() < 3) {
    st.reason = "fewer than 3 correspondences";
    return st;
  }
  const KeptPairs kept = KeepPairs(pairs, o);
  if (kept.count < 3) {
    st.reason = "fewer than 3 pairs after rejection";
    return st;
  }
  const double reject = kept.reject, c = kept.cauchy, radius = kept.radius;
  const Eigen::Vector2d& centroid = kept.centroid;

  // Equation 4.4 in 2D: A_i = [p x n / radius, n], b_i = n . (p - y).
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  double weight_sum = 0, weighed_r2 = 0;
  for (const Row& q : rows) {
    if (q.d > reject) continue;
    const Eigen::Vector2d p = q.p - centroid;
    const Eigen::Vector3d a((p.x() * q.n.y() - p.y() * q.n.x()) / radius, q.n.x(), q.n.y());
    const double w = q.w * (o.cauchy_scale_factor > 0 ? 1.0 / (1.0 + (q.r / c) * (q.r / c)) : 1.0);
    H.noalias() += w * a * a.transpose();
    g.noalias() += w * a * q.r;
    weight_sum += w;
    weighed_r2 += w * q.r * q.r;
  }
  // A pair's residual variance over its weight (a voxel's mean of w points has 1/w of a
  // point's): the residual noise per unit weight.
  const double noise2 = weighed_r2 / static_cast<double>(kept.count);
  if (translation_only) {
    H.row(0).setZero();
    H.col(0).setZero();
    g(0) = 0;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(H);
  st.eigenvalues = eig.eigenvalues();
  st.eigenvectors = eig.eigenvectors();
  // A row's theta entry is its (p - centroid) x n over the radius: times the radius, it is
  // the row for theta itself.
  const Eigen::DiagonalMatrix<double, 3> unscale(radius, 1.0, 1.0);
  st.H = unscale * H * unscale;  // back to (theta, x, y)
  st.centroid = centroid;
  // Solve in the eigenbasis, dropping the directions the data does not constrain
  // (solution remapping, Zhang and Singh 2016): the update never moves along them.
  const double floor = std::max(o.degeneracy_ratio * weight_sum, 1e-12 * weight_sum);
  Eigen::Vector3d delta_scaled = Eigen::Vector3d::Zero();
  Eigen::Vector3d variance_scaled = Eigen::Vector3d::Zero();  // of (radius theta, x, y) / s^2
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d v = st.eigenvectors.col(i);
    const double lambda = st.eigenvalues(i);
    if (translation_only && std::abs(v(0)) > 0.5) continue;  // the zeroed rotation axis
    if (lambda <= floor) {
      st.degenerate.push_back(v);
      continue;
    }
    delta_scaled -= v * (v.dot(g) / lambda);
    variance_scaled += v.cwiseProduct(v) / lambda;  // the step along v varies as s^2 / lambda
  }
  if (noise2 > 0 && st.degenerate.empty()) {
    st.noise_translation_m = std::sqrt(noise2 * (variance_scaled(1) + variance_scaled(2)));
    st.noise_rotation_rad = std::sqrt(noise2 * variance_scaled(0)) / radius;
  }
  if (st.degenerate.size() == (translation_only ? 2u : 3u)) {
    st.reason = "no direction constrained";
    return st;
  }
  st.delta = Eigen::Vector3d(delta_scaled(0) / radius, delta_scaled(1), delta_scaled(2));
  if (!st.delta.allFinite()) {
    st.reason = "non-finite update";
    return st;
  }
  st.ok = true;
  return st;
}

// Rotation by theta about centre c, then translation t: p -> R(p - c) + c + t.
Se2 AboutCentre(double theta, const Eigen::Vector2d& c, const Eigen::Vector2d& t) {
  const Se2 R{theta, {0, 0}};
  return {theta, c + t - R.R() * c};
}

// Fills the result's matrices from the last step and its fit statistics: from the last
// pass's point-to-line rows (one per point) when given, else from a fresh pass.
void Finish(const std::vector<Eigen::Vector2d>& points, const ClosestWallIndex& index,
            const IcpOptions& o, const Step& last, RegistrationResult* result,
            const std::vector<Row>* final_rows = nullptr) {
  result->normal_matrix = last.H;
  result->eigenvalues = last.eigenvalues;
  result->eigenvectors = last.eigenvectors;
  result->degenerate_directions = last.degenerate;
  if (!final_rows) {
    EvaluateFit(points, index, result->T_plan_slam, o.max_correspondence_m, o.inlier_threshold_m,
                result, nullptr);
    return;
  }
  double sum_matched = 0, sum_inlier = 0, matched_weight = 0, inlier_weight = 0;
  for (const Row& q : *final_rows) {
    sum_matched += q.w * q.d * q.d;
    matched_weight += q.w;
    if (q.d <= o.inlier_threshold_m) {
      sum_inlier += q.w * q.d * q.d;
      inlier_weight += q.w;
    }
  }
  const auto matched = static_cast<uint32_t>(matched_weight);
  const auto inliers = static_cast<uint32_t>(inlier_weight);
  result->points = static_cast<uint32_t>(points.size());
  result->matched = matched;
  result->inliers = inliers;
  result->rmse = matched ? std::sqrt(sum_matched / matched_weight) : 0.0;
  result->inlier_rmse = inliers ? std::sqrt(sum_inlier / inlier_weight) : 0.0;
}

// Algorithm 4.2's h_max, raised until the coarsest level has at most coarsest_points.
int TopLevel(size_t points, const IcpOptions& o) {
  int h = static_cast<int>(o.levels);
  while (h < 16 && o.coarsest_points > 0 && (points >> h) > o.coarsest_points) ++h;
  return h;
}

// Mean of min(d, max_corr)^2 over every stride-th point: the "better fit" score.
double TruncatedScore(const std::vector<Eigen::Vector2d>& points, size_t stride, const Se2& T,
                      const ClosestWallIndex& index, double max_corr) {
  const Eigen::Matrix2d R = T.R();
  const double cap2 = max_corr * max_corr;
  double sum = 0;
  size_t n = 0;
  for (size_t i = 0; i < points.size(); i += stride, ++n) {
    const auto hit = index.Query(R * points[i] + T.t);
    sum += hit ? std::min(hit->distance * hit->distance, cap2) : cap2;
  }
  return n ? sum / n : cap2;
}

bool SmallStep(const Eigen::Vector3d& delta, const IcpOptions& o) {
  return std::abs(delta(0)) < o.converge_rotation_rad &&
         delta.tail<2>().norm() < o.converge_translation_m;
}

// The points that fit a wall under a reference transform (within a threshold), with
// their walls' normals, found once: WallNormalShift of other transforms against it.
class FittingPoints {
 public:
  FittingPoints(const std::vector<Eigen::Vector2d>& points, const ClosestWallIndex& index,
                const Se2& T, double threshold_m)
      : points_(&points), T_(T) {
    for (size_t i = 0; i < points.size(); ++i) {
      const auto hit = index.Query(T * points[i]);
      if (hit && hit->distance <= threshold_m) fitting_.emplace_back(i, hit->normal);
    }
  }
  const Se2& T() const { return T_; }
  // RMS shift of the fitting points along their walls' normals under T_b, metres.
  double ShiftTo(const Se2& T_b) const {
    double sum2 = 0;
    for (const auto& [i, n] : fitting_) {
      const Eigen::Vector2d& p = (*points_)[i];
      const double across = n.dot(T_b * p - T_ * p);
      sum2 += across * across;
    }
    return fitting_.empty() ? 0.0 : std::sqrt(sum2 / static_cast<double>(fitting_.size()));
  }

 private:
  const std::vector<Eigen::Vector2d>* points_;
  Se2 T_;
  std::vector<std::pair<size_t, Eigen::Vector2d>> fitting_;  // point index, wall normal
};

}  // namespace

RegistrationResult RegisterIcp(const std::vector<Eigen::Vector2d>& cloud,
                               const ClosestWallIndex& index, const Se2& initial,
                               const IcpOptions& o) {
  // A voxel's mean weighs as all of the voxel's points: the fit is the whole cloud's, at
  // the cost of one point per voxel.
  VoxelCloud thinned;
  if (o.voxel_m > 0) thinned = VoxelMeans(cloud, o.voxel_m);
  const std::vector<Eigen::Vector2d>& points = o.voxel_m > 0 ? thinned.points : cloud;
  const std::vector<uint32_t>* counts = o.voxel_m > 0 ? &thinned.counts : nullptr;
  RegistrationResult result;
  result.method = "icp";
  result.T_plan_slam = initial;
  Se2 T = initial;
  Pairs pairs;
  pairs.rows.reserve(points.size());
  Step last;
  bool converged_at_finest = false;
  // Algorithm 4.2: coarse to fine; level h uses every 2^h-th point. Once a level's fit
  // is known within the convergence thresholds (its points' noise leaves it no more
  // uncertain), the finer levels could only confirm it: the levels between are skipped,
  // and the finest, whose first step is then below the thresholds, polishes once.
  for (int h = TopLevel(points.size(), o), next = h; h >= 0 && result.reason.empty(); h = next) {
    next = h - 1;
    const size_t stride = size_t{1} << h;
    bool converged = false;
    for (uint32_t it = 0; it < o.max_iterations; ++it) {
      ++result.iterations;
      MakeRows(points, counts, stride, T, index, o.max_correspondence_m, false, &pairs);
      // Plain least squares on the coarse levels: a kernel whose scale follows the median
      // residual collapses on clean data once half the points fit, and then ignores the
      // points that would pull the cloud out of a wrong minimum.
      IcpOptions level_o = o;
      if (h > 0) level_o.cauchy_scale_factor = 0;
      Step st = SolveStep(pairs, level_o, false);
      if (!st.ok) {
        result.reason = st.reason;
        break;
      }
      T = AboutCentre(st.delta(0), st.centroid, st.delta.tail<2>()) * T;
      last = std::move(st);
      converged = SmallStep(last.delta, o);
      if (converged) break;
    }
    converged_at_finest = converged;
    if (h > 0 && last.noise_translation_m <= o.converge_translation_m &&
        last.noise_rotation_rad <= o.converge_rotation_rad)
      next = 0;
  }
  result.T_plan_slam = T;
  result.converged = result.reason.empty() && converged_at_finest;
  if (result.reason.empty() && !result.converged) result.reason = "iteration limit";
  if (result.converged) {
    // The last pass paired every point (level 0) and the step after it was below the
    // convergence threshold: its distances are the fit's, without another full pass.
    Finish(cloud, index, o, last, &result, &pairs.rows);
  } else {
    Finish(cloud, index, o, last, &result);
  }
  return result;
}

RegistrationResult RegisterIk(const std::vector<Eigen::Vector2d>& points,
                              const ClosestWallIndex& index, const Se2& initial,
                              const IcpOptions& o) {
  RegistrationResult result;
  result.method = "ik";
  Se2 T = initial;
  Pairs pairs;
  pairs.rows.reserve(points.size());
  Step last;
  bool converged_at_finest = false;
  // The same coarse-to-fine levels as ICP (Algorithm 4.2), each with Algorithm 4.3.
  for (int h = TopLevel(points.size(), o); h >= 0 && result.reason.empty(); --h) {
    const size_t stride = size_t{1} << h;
    // Every level may iterate to convergence: coarse iterations are cheap, and a level
    // that stops early only hands its work to a finer, dearer one.
    const uint32_t max_iter = o.max_iterations;
    double score = TruncatedScore(points, stride, T, index, o.inlier_threshold_m);
    bool converged = false;
    for (uint32_t it = 0; it < max_iter; ++it) {
      ++result.iterations;
      MakeRows(points, nullptr, stride, T, index, o.max_correspondence_m, true, &pairs);
      IcpOptions level_o = o;  // as in ICP: plain least squares on the coarse levels
      if (h > 0) level_o.cauchy_scale_factor = 0;
      Step st = SolveStep(pairs, level_o, false);  // Algorithm 4.4
      if (!st.ok) {
        result.reason = st.reason;
        break;
      }
      // Algorithm 4.5 in 2D: v(x) = c_bar + omega J (x - centroid) vanishes at the
      // instantaneous centre G = centroid + J c_bar / omega; the rigid motion is the
      // rotation by omega about G (a translation by c_bar when omega is ~0).
      const double omega = st.delta(0);
      const Eigen::Vector2d c_bar = st.delta.tail<2>();
      bool improved = false;
      for (double scale = 1.0; scale > 1.0 / 32; scale *= 0.5) {
        Se2 motion;
        if (std::abs(omega * scale) < 1e-12) {
          motion = {0.0, c_bar * scale};
        } else {
          const Eigen::Vector2d G = st.centroid + Eigen::Vector2d(-c_bar.y(), c_bar.x()) / omega;
          motion = AboutCentre(omega * scale, G, Eigen::Vector2d::Zero());
        }
        const Se2 candidate = motion * T;
        const double candidate_score =
            TruncatedScore(points, stride, candidate, index, o.inlier_threshold_m);
        if (candidate_score <= score) {  // Algorithm 4.3 line 9: only a better fit
          T = candidate;
          score = candidate_score;
          improved = true;
          break;
        }
      }
      last = std::move(st);
      if (!improved || SmallStep(last.delta, o)) {
        converged = true;  // no better fit nearby: a minimum at this level
        break;
      }
    }
    converged_at_finest = converged;
  }
  result.T_plan_slam = T;
  result.converged = result.reason.empty() && converged_at_finest;
  if (result.reason.empty() && !result.converged) result.reason = "iteration limit";
  Finish(points, index, o, last, &result);
  return result;
}

std::optional<double> HoughRotation(const std::vector<Eigen::Vector2d>& points,
                                    const std::vector<Eigen::Vector2d>& normals,
                                    const ClosestWallIndex& index, const Se2& initial,
                                    const HoughOptions& h) {
  if (normals.size() != points.size() || points.empty()) return std::nullopt;
  // Equation 4.6: a point with a normal is a line, theta = atan2(n.y, n.x); walls are
  // two-sided, so angles are taken modulo pi. Histograms of the cloud (in the plan frame
  // under the initial guess, one vote a point) and of the plan (wall length).
  const int bins = std::max(8, static_cast<int>(std::lround(M_PI / h.bin_rad)));
  const double bin = M_PI / bins;
  std::vector<double> cloud_hist(bins, 0.0), plan_hist(bins, 0.0);
  const Eigen::Matrix2d R0 = initial.R();
  auto vote = [&](std::vector<double>& hist, const Eigen::Vector2d& n, double w) {
    double a = std::atan2(n.y(), n.x());
    a = std::fmod(a + 2 * M_PI, M_PI) / bin - 0.5;  // in bins, centres at integers
    const double f = std::floor(a);
    const int i = ((static_cast<int>(f) % bins) + bins) % bins;
    hist[i] += w * (1 - (a - f));
    hist[(i + 1) % bins] += w * (a - f);
  };
  for (const Eigen::Vector2d& n : normals)
    if (n.allFinite() && n.squaredNorm() > 1e-12) vote(cloud_hist, R0 * n, 1.0);
  // Only the walls near the cloud vote: a wing of the building turned by a few degrees
  // must not pull the rotation of a scan taken elsewhere.
  Eigen::Vector2d lo = initial * points.front(), hi = lo;
  for (const Eigen::Vector2d& p : points) {
    lo = lo.cwiseMin(initial * p);
    hi = hi.cwiseMax(initial * p);
  }
  const Eigen::Vector2d margin = Eigen::Vector2d::Constant(2.0);
  for (const Segment& s : ClipFloorPlan(index.plan(), lo - margin, hi + margin).segments)
    vote(plan_hist, s.Normal(), s.Length());
  // Gaussian smoothing (circular) makes the correlation peak well-defined.
  const int half = std::max(1, static_cast<int>(std::ceil(3 * h.smooth_rad / bin)));
  auto smooth = [&](const std::vector<double>& in) {
    std::vector<double> out(bins, 0.0);
    for (int i = 0; i < bins; ++i)
      for (int k = -half; k <= half; ++k) {
        const double x = k * bin / h.smooth_rad;
        out[i] += in[((i + k) % bins + bins) % bins] * std::exp(-0.5 * x * x);
      }
    return out;
  };
  cloud_hist = smooth(cloud_hist);
  plan_hist = smooth(plan_hist);
  // Algorithm 4.6 lines 5-16: the rotation whose shifted histogram agrees best.
  const int max_shift = static_cast<int>(std::floor(h.max_rotation_rad / bin));
  std::vector<double> score(2 * max_shift + 1, 0.0);
  for (int s = -max_shift; s <= max_shift; ++s) {
    double sum = 0;
    for (int b = 0; b < bins; ++b) sum += cloud_hist[b] * plan_hist[((b + s) % bins + bins) % bins];
    score[s + max_shift] = sum;
  }
  const int best = static_cast<int>(std::max_element(score.begin(), score.end()) - score.begin());
  if (score[best] <= 0) return std::nullopt;
  double shift = best - max_shift;
  if (best > 0 && best + 1 < static_cast<int>(score.size())) {  // parabolic refinement
    const double l = score[best - 1], c = score[best], r = score[best + 1];
    const double denom = l - 2 * c + r;
    if (denom < 0) shift += 0.5 * (l - r) / denom;
  }
  return shift * bin;
}

RegistrationResult RegisterHough(const std::vector<Eigen::Vector2d>& points,
                                 const std::vector<Eigen::Vector2d>& normals,
                                 const ClosestWallIndex& index, const Se2& initial,
                                 const IcpOptions& o, const HoughOptions& h) {
  RegistrationResult result;
  result.method = "hough";
  result.T_plan_slam = initial;
  if (normals.size() != points.size() || points.size() < 3) {
    result.reason = "Hough needs a normal for every point";
    Finish(points, index, o, Step{}, &result);
    return result;
  }
  const std::optional<double> rotation = HoughRotation(points, normals, index, initial, h);
  if (!rotation) {
    result.reason = "no wall directions to turn by";
    Finish(points, index, o, Step{}, &result);
    return result;
  }
  const double omega = *rotation;
  // Rotate about the cloud's centroid in the plan frame, so the rotation does not swing
  // the cloud away from where the initial guess put it.
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& p : points) centroid += initial * p;
  centroid /= static_cast<double>(points.size());
  Se2 T = AboutCentre(omega, centroid, Eigen::Vector2d::Zero()) * initial;

  // Algorithm 4.7, point-to-line: translation-only steps until they vanish.
  Pairs pairs;
  Step last;
  for (uint32_t it = 0; it < o.max_iterations; ++it) {
    ++result.iterations;
    MakeRows(points, nullptr, 1, T, index, o.max_correspondence_m, false, &pairs);
    Step st = SolveStep(pairs, o, true);
    if (!st.ok) {
      result.reason = st.reason;
      break;
    }
    T = Se2{0.0, st.delta.tail<2>()} * T;
    last = std::move(st);
    if (SmallStep(last.delta, o)) {
      result.converged = true;
      break;
    }
  }
  result.T_plan_slam = T;
  if (result.reason.empty() && !result.converged) result.reason = "iteration limit";
  Finish(points, index, o, last, &result);
  return result;
}

std::vector<Se2> CorrelativeSearch(const std::vector<Eigen::Vector2d>& points,
                                   const ClosestWallIndex& index, const Se2& initial,
                                   const RegistrationOptions& options) {
  constexpr size_t kSample = 200;
  constexpr double kStepM = 0.4;  // translation grid
  constexpr double kStepRad = 1.5 * M_PI / 180;
  constexpr double kSigma = 0.4;  // score kernel: 1 - d^2 / sigma^2, clipped at 0
  if (points.empty()) return {};
  const size_t stride = std::max<size_t>(1, points.size() / kSample);
  std::vector<Eigen::Vector2d> sample;
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < points.size(); i += stride) {
    sample.push_back(initial * points[i]);
    centroid += sample.back();
  }
  centroid /= static_cast<double>(sample.size());
  const int nt = static_cast<int>(std::floor(options.search_window_m / kStepM));
  const int nr = static_cast<int>(std::floor(options.search_window_rad / kStepRad));
  struct Candidate {
    double score;
    Se2 T;  // correction in the plan frame, applied after `initial`
  };
  std::vector<Candidate> all;
  std::vector<Eigen::Vector2d> rotated(sample.size());
  std::optional<Eigen::Matrix3d> information;
  if (options.search_covariance && options.search_pivot)
    information = options.search_covariance->inverse();
  const double max_d2 = options.search_max_sigmas * options.search_max_sigmas;
  for (int ir = -nr; ir <= nr; ++ir) {
    const Se2 rotation = AboutCentre(ir * kStepRad, options.search_pivot.value_or(centroid),
                                     Eigen::Vector2d::Zero());
    for (size_t i = 0; i < sample.size(); ++i) rotated[i] = rotation * sample[i];
    for (int ix = -nt; ix <= nt; ++ix) {
      for (int iy = -nt; iy <= nt; ++iy) {
        const Eigen::Vector2d t(ix * kStepM, iy * kStepM);
        if (information) {
          const Eigen::Vector3d delta(ir * kStepRad, t.x(), t.y());
          if (delta.dot(*information * delta) > max_d2) continue;
        }
        double score = 0;
        for (const Eigen::Vector2d& p : rotated) {
          const auto hit = index.Query(p + t);
          if (hit && hit->distance < kSigma)
            score += 1.0 - hit->distance * hit->distance / (kSigma * kSigma);
        }
        all.push_back({score, Se2{0.0, t} * rotation});
      }
    }
  }
  std::sort(all.begin(), all.end(),
            [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  // The best few places: a candidate is the same place as a better one when it moves
  // the sample points that fit a wall there less than kDistinctShiftM across their walls
  // (WallNormalShift, on the sample): slid along a corridor, or a grid step off.
  std::vector<FittingPoints> kept;
  for (const Candidate& c : all) {
    if (kept.size() >= options.search_candidates) break;
    bool same = false;
    for (const FittingPoints& k : kept) same = same || k.ShiftTo(c.T) <= kDistinctShiftM;
    if (!same) kept.emplace_back(sample, index, c.T, kSigma);
  }
  std::vector<Se2> out;
  for (const FittingPoints& k : kept) out.push_back(k.T() * initial);
  return out;
}

double WallNormalShift(const std::vector<Eigen::Vector2d>& points, const ClosestWallIndex& index,
                       const Se2& T_a, const Se2& T_b, double inlier_threshold_m) {
  return FittingPoints(points, index, T_a, inlier_threshold_m).ShiftTo(T_b);
}

RegistrationResult Register(const std::vector<Eigen::Vector2d>& points,
                            const std::vector<Eigen::Vector2d>& normals,
                            const ClosestWallIndex& index, const Se2& initial,
                            const RegistrationOptions& options) {
  const std::vector<Eigen::Vector2d>* use_points = &points;
  const std::vector<Eigen::Vector2d>* use_normals = &normals;
  std::vector<Eigen::Vector2d> kept_points, kept_normals;
  if (options.wall_buffer_m > 0) {
    // The thesis' buffer (section 6.4.3): points far from every wall under the current
    // alignment are furniture or people, not walls.
    for (size_t i = 0; i < points.size(); ++i) {
      const auto hit = index.Query(initial * points[i]);
      if (!hit || hit->distance > options.wall_buffer_m) continue;
      kept_points.push_back(points[i]);
      if (i < normals.size()) kept_normals.push_back(normals[i]);
    }
    use_points = &kept_points;
    use_normals = &kept_normals;
  }
  const ClosestWallIndex* use_index = &index;
  std::optional<ClosestWallIndex> clipped;
  if (options.clip_margin_m > 0 && !use_points->empty()) {
    Eigen::Vector2d lo = initial * use_points->front(), hi = lo;
    for (const Eigen::Vector2d& p : *use_points) {
      lo = lo.cwiseMin(initial * p);
      hi = hi.cwiseMax(initial * p);
    }
    const Eigen::Vector2d margin = Eigen::Vector2d::Constant(options.clip_margin_m);
    FloorPlan plan = ClipFloorPlan(index.plan(), lo - margin, hi + margin);
    if (plan.segments.empty()) {
      RegistrationResult r;
      r.method = ToString(options.method);
      r.T_plan_slam = initial;
      r.points = static_cast<uint32_t>(use_points->size());
      r.reason = "no plan walls near the points";
      return r;
    }
    clipped.emplace(plan);
    use_index = &*clipped;
  }
  auto refine = [&](const Se2& start) -> RegistrationResult {
    switch (options.method) {
      case RegistrationMethod::kIcp:
        return RegisterIcp(*use_points, *use_index, start, options.icp);
      case RegistrationMethod::kIk: return RegisterIk(*use_points, *use_index, start, options.icp);
      case RegistrationMethod::kHough:
        return RegisterHough(*use_points, *use_normals, *use_index, start, options.icp,
                             options.hough);
    }
    return {};
  };
  if (options.search_window_m <= 0 && options.search_window_rad <= 0) return refine(initial);
  std::vector<Se2> starts = CorrelativeSearch(*use_points, *use_index, initial, options);
  starts.insert(starts.begin(), initial);
  std::vector<std::pair<double, RegistrationResult>> fits;
  uint32_t iterations = 0;
  for (const Se2& start : starts) {
    RegistrationResult r = refine(start);
    iterations += r.iterations;
    double score = 0;
    // Capped at the inlier threshold: with a 1.5 m cap, clutter far from the walls
    // outweighs the walls and prefers a pose 10-20 cm off.
    EvaluateFit(*use_points, *use_index, r.T_plan_slam, options.icp.inlier_threshold_m,
                options.icp.inlier_threshold_m, nullptr, &score);
    fits.emplace_back(score, std::move(r));
  }
  std::stable_sort(fits.begin(), fits.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  // Places that score about the same are told apart by the initial guess: the nearest
  // at the search's pivot, else at the cloud's centre, wins (a wall seen alone fits every
  // place along it equally).
  if (options.search_tie_ratio > 0) {
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    if (options.search_pivot) {
      centre = initial.Inverse() * *options.search_pivot;
    } else {
      for (const Eigen::Vector2d& p : *use_points) centre += p;
      centre /= static_cast<double>(std::max<size_t>(1, use_points->size()));
    }
    const Eigen::Vector2d guess = initial * centre;
    size_t nearest = 0;
    for (size_t i = 1; i < fits.size(); ++i) {
      if (fits[i].first * options.search_tie_ratio > fits.front().first) break;
      if ((fits[i].second.T_plan_slam * centre - guess).norm() <
          (fits[nearest].second.T_plan_slam * centre - guess).norm())
        nearest = i;
    }
    std::swap(fits[0], fits[nearest]);
  }
  RegistrationResult best = std::move(fits.front().second);
  best.iterations = iterations;
  // Another place only when it moves the walls that fit off their lines: the same
  // corridor slid along its axis is not another place (the walls cannot tell, and the
  // initial guess keeps its position along the axis).
  const FittingPoints best_fit(*use_points, *use_index, best.T_plan_slam,
                               options.icp.inlier_threshold_m);
  for (size_t i = 1; i < fits.size(); ++i) {
    if (best_fit.ShiftTo(fits[i].second.T_plan_slam) <= kDistinctShiftM) continue;
    best.ambiguity = fits[i].first > 0 ? std::min(1.0, fits.front().first / fits[i].first) : 1.0;
    break;
  }
  return best;
}

}  // namespace floorpose
