// Synthetic scans with a known answer for the registration tests (core and real plans):
// the wall points a walker would see in a window of the plan, moved into the slam frame
// by a known T_slam_plan, with Gaussian noise and clutter, and an initial guess that is
// the truth with a seeded error about the window's centre.
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "core/closest_wall_index.h"
#include "core/floor_plan.h"
#include "core/random.h"
#include "core/registration.h"
#include "core/se2.h"
#include "tests/test_util.h"

namespace floorpose::testing {

// An axis-aligned window of the plan, metres.
struct Box {
  Eigen::Vector2d min = Eigen::Vector2d::Zero(), max = Eigen::Vector2d::Zero();
  Eigen::Vector2d Centre() const { return 0.5 * (min + max); }
  bool Contains(const Eigen::Vector2d& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
  static Box Around(const Eigen::Vector2d& centre, double size_m) {
    const Eigen::Vector2d half = Eigen::Vector2d::Constant(0.5 * size_m);
    return {centre - half, centre + half};
  }
};

struct ScanOptions {
  double spacing_m = 0.05;        // between wall points along a wall
  double noise_m = 0.0;           // Gaussian, per axis
  double normal_noise_rad = 0.0;  // Gaussian, on the wall points' normal angles
  double clutter_share = 0.0;     // clutter points / all points
  // Clutter is drawn uniformly in the window but not this close to a wall: it stands
  // for furniture and people, not for the walls themselves.
  double clutter_clearance_m = 0.15;
};

// Wall points and their normals in the slam frame.
struct Scan {
  std::vector<Eigen::Vector2d> points, normals;
  size_t wall_points = 0;  // the first wall_points are on walls, the rest clutter
};

// The walls inside `window` sampled every spacing_m (both faces of a thick wall: a walker
// sees each from its own room), moved to slam by T_slam_plan, plus clutter with random
// normals. A wall's normal gets a random sign, as walls are two-sided.
inline Scan MakeScan(const FloorPlan& plan, const Box& window, const Se2& T_slam_plan,
                     const ScanOptions& o, SplitMix64& rng) {
  Scan scan;
  const Eigen::Matrix2d R = T_slam_plan.R();
  for (const Segment& s : plan.segments) {
    const double sign = rng.Uniform() < 0.5 ? -1.0 : 1.0;
    const int n = std::max(1, static_cast<int>(std::ceil(s.Length() / o.spacing_m)));
    for (int i = 0; i <= n; ++i) {
      const Eigen::Vector2d p = s.a + (s.b - s.a) * (static_cast<double>(i) / n);
      if (!window.Contains(p)) continue;
      const Eigen::Vector2d noise(rng.Gaussian(), rng.Gaussian());
      const double a = o.normal_noise_rad * rng.Gaussian();
      const Eigen::Vector2d n_plan = Eigen::Rotation2Dd(a) * s.Normal() * sign;
      scan.points.push_back(T_slam_plan * (p + o.noise_m * noise));
      scan.normals.push_back(R * n_plan);
    }
  }
  scan.wall_points = scan.points.size();
  if (o.clutter_share > 0 && o.clutter_share < 1) {
    const size_t want = static_cast<size_t>(
        std::lround(o.clutter_share / (1 - o.clutter_share) * scan.wall_points));
    const ClosestWallIndex index(plan, {0.5, o.clutter_clearance_m + 0.5});
    for (size_t tries = 0; scan.points.size() < scan.wall_points + want && tries < 100 * want;
         ++tries) {
      const Eigen::Vector2d p = RandomVector2(rng, window.min, window.max);
      const auto hit = index.Query(p);
      if (hit && hit->distance < o.clutter_clearance_m) continue;
      const double a = rng.Uniform(-M_PI, M_PI);
      scan.points.push_back(T_slam_plan * p);
      scan.normals.push_back({std::cos(a), std::sin(a)});
    }
  }
  return scan;
}

// Total wall length inside a window (sampled at 5 cm), metres.
inline double WallLengthIn(const FloorPlan& plan, const Box& window) {
  double length = 0;
  for (const Segment& s : plan.segments) {
    const int n = std::max(1, static_cast<int>(std::ceil(s.Length() / 0.05)));
    for (int i = 0; i < n; ++i)
      if (window.Contains(s.a + (s.b - s.a) * ((i + 0.5) / n))) length += s.Length() / n;
  }
  return length;
}

// How well a window's walls pin down all three unknowns: the smallest eigenvalue of the
// point-to-line normal matrix (theta as arc length at the RMS radius, as in
// RegistrationResult::eigenvalues) over the mean, for wall points every 5 cm. Near 0
// for a corridor, about 1 for a room seen whole.
inline double ConstraintStrength(const FloorPlan& plan, const Box& window) {
  std::vector<Eigen::Vector2d> points, normals;
  for (const Segment& s : plan.segments) {
    const int n = std::max(1, static_cast<int>(std::ceil(s.Length() / 0.05)));
    for (int i = 0; i <= n; ++i) {
      const Eigen::Vector2d p = s.a + (s.b - s.a) * (static_cast<double>(i) / n);
      if (!window.Contains(p)) continue;
      points.push_back(p);
      normals.push_back(s.Normal());
    }
  }
  if (points.size() < 3) return 0;
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  double radius2 = 0;
  for (const auto& p : points) radius2 += (p - centroid).squaredNorm();
  const double radius = std::sqrt(radius2 / points.size());
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d p = points[i] - centroid, n = normals[i];
    const Eigen::Vector3d a((p.x() * n.y() - p.y() * n.x()) / radius, n.x(), n.y());
    H += a * a.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(H);
  return eig.eigenvalues()(0) / (H.trace() / 3);
}

// The truth with an error: a rotation by dtheta about `centre_plan` (the walker's area,
// so the error does not grow with the distance to the plan's origin), then a shift by dt.
inline Se2 PerturbAbout(const Se2& T_plan_slam, const Eigen::Vector2d& centre_plan, double dtheta,
                        const Eigen::Vector2d& dt) {
  const Se2 rotation{dtheta, {0, 0}};
  const Se2 error{dtheta, centre_plan + dt - rotation.R() * centre_plan};
  return error * T_plan_slam;
}

// A seeded error: angle uniform in [-max, max], shift of length uniform in [0, max] in a
// uniform direction (so large errors are as common as small ones).
struct InitialError {
  double theta = 0;
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
};
inline InitialError RandomError(SplitMix64& rng, double max_angle_rad, double max_shift_m) {
  const double direction = rng.Uniform(-M_PI, M_PI);
  const double length = rng.Uniform(0, max_shift_m);
  return {rng.Uniform(-max_angle_rad, max_angle_rad),
          length * Eigen::Vector2d(std::cos(direction), std::sin(direction))};
}

// How far an estimate is from the truth where it matters: the rotation, and the
// displacement of the window's centre (in the plan frame).
struct PoseError {
  double rotation_rad = 0;
  double translation_m = 0;
};
inline PoseError ErrorAt(const Se2& estimate, const Se2& truth, const Eigen::Vector2d& centre) {
  const Se2 e = estimate * truth.Inverse();  // plan -> plan
  return {std::abs(WrapAngle(e.theta)), (e * centre - centre).norm()};
}

inline std::string Describe(const PoseError& e) {
  std::ostringstream ss;
  ss.precision(3);
  ss << std::fixed << e.translation_m * 100 << " cm, " << e.rotation_rad * 180 / M_PI << " deg";
  return ss.str();
}

// Tallies the cases of one (plan, method, condition): how many met the tolerance and
// the worst errors, for the log line a test prints (a failing case also fails on its own).
struct Tally {
  int cases = 0, failed = 0;
  double worst_translation_m = 0, worst_rotation_rad = 0;
  std::vector<double> translations_m;
  void Add(const PoseError& e, bool ok) {
    ++cases;
    failed += ok ? 0 : 1;
    worst_translation_m = std::max(worst_translation_m, e.translation_m);
    worst_rotation_rad = std::max(worst_rotation_rad, e.rotation_rad);
    translations_m.push_back(e.translation_m);
  }
  double MedianTranslation() const {
    if (translations_m.empty()) return 0;
    std::vector<double> v = translations_m;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  }
  std::string Summary() const {
    std::ostringstream ss;
    ss.precision(2);
    ss << std::fixed << (cases - failed) << "/" << cases << " within tolerance; median "
       << MedianTranslation() * 100 << " cm; worst " << worst_translation_m * 100 << " cm, "
       << worst_rotation_rad * 180 / M_PI << " deg";
    return ss.str();
  }
};

// One requirement of issue 3: the scan's noise and clutter, the initial error, and the
// tolerance the result must meet.
struct Condition {
  std::string name;
  ScanOptions scan;
  double max_angle_rad = 0, max_shift_m = 0;  // initial error
  double tolerance_m = 0, tolerance_rad = 0;  // translation tolerance ignored if rotation_only
  bool rotation_only = false;                 // Hough: only the rotation is required
};

// Clean wall points, errors up to 10 degrees and 2 m: within 2 cm and 0.2 degrees.
inline Condition Clean() { return {"clean", {}, Deg(10), 2.0, 0.02, Deg(0.2), false}; }

// 4 cm noise per axis (and 2 degrees on the normals), clutter 30% of all points, errors
// up to 10 degrees and 2 m: within 10 cm and 1 degree.
inline Condition NoisyCluttered() {
  ScanOptions scan;
  scan.noise_m = 0.04;
  scan.normal_noise_rad = Deg(2);
  scan.clutter_share = 0.3;
  return {"noisy", scan, Deg(10), 2.0, 0.10, Deg(1), false};
}

// Hough's rotation from errors up to 30 degrees (and 2 m): within 1 degree.
inline Condition HoughRotation(const Condition& base) {
  Condition c = base;
  c.name = base.name + "-30deg";
  c.max_angle_rad = Deg(30);
  c.tolerance_rad = Deg(1);
  c.rotation_only = true;
  return c;
}

// Runs `cases` seeded registrations in each window: a random T_slam_plan, the scan of
// the window, the truth perturbed by a random error. Tallies the errors; describes each
// case that misses the tolerance in `failures`.
inline Tally RunCases(const FloorPlan& plan, const ClosestWallIndex& index,
                      const std::vector<Box>& windows, int cases, RegistrationMethod method,
                      const Condition& condition, uint64_t seed,
                      std::vector<std::string>* failures) {
  Tally tally;
  SplitMix64 rng(seed);
  RegistrationOptions options;
  options.method = method;
  // The initial guess can be 2 m off, as a wall pick can: the correlative search in front
  // of the method is what gets it out of a neighbouring room's walls. Hough searches
  // rotation itself, so it only gets the translation window.
  options.search_window_m = condition.max_shift_m + 0.5;
  options.search_window_rad =
      method == RegistrationMethod::kHough ? 0.0 : condition.max_angle_rad + 0.05;
  for (const Box& window : windows) {
    for (int k = 0; k < cases; ++k) {
      const Se2 T_slam_plan = RandomSe2(rng, M_PI, 30.0);
      const Se2 truth = T_slam_plan.Inverse();
      const Scan scan = MakeScan(plan, window, T_slam_plan, condition.scan, rng);
      const InitialError e = RandomError(rng, condition.max_angle_rad, condition.max_shift_m);
      const Se2 initial = PerturbAbout(truth, window.Centre(), e.theta, e.t);
      const RegistrationResult r = Register(scan.points, scan.normals, index, initial, options);
      const PoseError error = ErrorAt(r.T_plan_slam, truth, window.Centre());
      const bool ok = error.rotation_rad <= condition.tolerance_rad &&
                      (condition.rotation_only || error.translation_m <= condition.tolerance_m);
      tally.Add(error, ok);
      if (ok || !failures) continue;
      // How well the wrong pose fits, against the truth. First by the score Register and
      // IK compare poses with (mean of min(d, 1.5 m)^2), then with the cap at the 20 cm
      // inlier threshold, which clutter cannot sway: a result no worse than the truth
      // under the tight score is ambiguous; worse means a local minimum.
      double wide_truth = 0, wide_result = 0, tight_truth = 0, tight_result = 0;
      EvaluateFit(scan.points, index, truth, 1.5, 0.2, nullptr, &wide_truth);
      EvaluateFit(scan.points, index, r.T_plan_slam, 1.5, 0.2, nullptr, &wide_result);
      EvaluateFit(scan.points, index, truth, 0.2, 0.2, nullptr, &tight_truth);
      EvaluateFit(scan.points, index, r.T_plan_slam, 0.2, 0.2, nullptr, &tight_result);
      std::ostringstream ss;
      ss.precision(2);
      ss << std::fixed << "window at (" << window.Centre().x() << ", " << window.Centre().y()
         << ") case " << k << ": initial " << e.theta * 180 / M_PI << " deg, " << e.t.norm()
         << " m -> " << Describe(error) << " (" << (r.converged ? "converged" : r.reason) << ", "
         << r.iterations << " iterations, " << scan.points.size() << " points; score (1.5 m cap) "
         << 1e4 * wide_result << " vs " << 1e4 * wide_truth << " cm^2 at the truth, (0.2 m cap) "
         << 1e4 * tight_result << " vs " << 1e4 * tight_truth << ": "
         << (tight_result <= tight_truth ? "ambiguous" : "local minimum") << ")";
      failures->push_back(ss.str());
    }
  }
  return tally;
}

// The first `max_lines` failures, one a line, for an assertion message.
inline std::string FirstLines(const std::vector<std::string>& lines, size_t max_lines = 12) {
  std::string out;
  for (size_t i = 0; i < lines.size() && i < max_lines; ++i) out += "\n  " + lines[i];
  if (lines.size() > max_lines)
    out += "\n  ... and " + std::to_string(lines.size() - max_lines) + " more";
  return out;
}

}  // namespace floorpose::testing
