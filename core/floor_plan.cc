#include "core/floor_plan.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <set>
#include <tuple>

namespace floorpose {

Eigen::Vector2d ClosestPointOnSegment(const Segment& s, const Eigen::Vector2d& p) {
  const Eigen::Vector2d d = s.b - s.a;
  const double len2 = d.squaredNorm();
  if (len2 <= 0.0) return s.a;
  const double u = std::clamp((p - s.a).dot(d) / len2, 0.0, 1.0);
  return s.a + u * d;
}

FloorPlanParse MakeFloorPlan(std::string id, std::vector<Segment> raw) {
  FloorPlanParse out;
  out.plan.id = std::move(id);
  // Duplicates are found on endpoints rounded to 1 mm, in either direction.
  std::set<std::tuple<long long, long long, long long, long long>> seen;
  auto mm = [](double v) { return std::llround(v * 1000.0); };
  for (Segment s : raw) {
    if (!s.a.allFinite() || !s.b.allFinite() || s.Length() < 1e-3) {
      ++out.dropped_segments;
      continue;
    }
    auto key = std::make_tuple(mm(s.a.x()), mm(s.a.y()), mm(s.b.x()), mm(s.b.y()));
    auto rev = std::make_tuple(mm(s.b.x()), mm(s.b.y()), mm(s.a.x()), mm(s.a.y()));
    if (seen.count(key) || seen.count(rev)) {
      ++out.dropped_segments;
      continue;
    }
    seen.insert(key);
    out.plan.segments.push_back(s);
  }
  if (out.plan.segments.empty()) {
    out.error = "floor plan has no usable wall segments";
    return out;
  }
  Eigen::Vector2d lo = out.plan.segments[0].a, hi = lo;
  for (const Segment& s : out.plan.segments) {
    lo = lo.cwiseMin(s.a).cwiseMin(s.b);
    hi = hi.cwiseMax(s.a).cwiseMax(s.b);
  }
  if (!(hi - lo).allFinite()) {
    out.error = "floor plan extent overflows (coordinates near the double limit)";
    return out;
  }
  out.plan.min = lo;
  out.plan.max = hi;
  return out;
}

FloorPlan ClipFloorPlan(const FloorPlan& plan, const Eigen::Vector2d& lo,
                        const Eigen::Vector2d& hi) {
  FloorPlan out;
  out.id = plan.id;
  for (const Segment& s : plan.segments) {
    const Eigen::Vector2d d = s.b - s.a;
    double t0 = 0, t1 = 1;
    bool inside = true;
    // Liang-Barsky: clip the parameter range against each of the four edges.
    for (int axis = 0; axis < 2 && inside; ++axis) {
      for (const double sign : {-1.0, 1.0}) {
        const double p = sign * d(axis);
        const double q = sign > 0 ? hi(axis) - s.a(axis) : s.a(axis) - lo(axis);
        if (p == 0) {
          if (q < 0) inside = false;
        } else if (p < 0) {
          t0 = std::max(t0, q / p);
        } else {
          t1 = std::min(t1, q / p);
        }
      }
    }
    if (!inside || t0 >= t1) continue;
    out.segments.push_back({s.a + t0 * d, s.a + t1 * d});
  }
  if (!out.segments.empty()) {
    out.min = out.segments[0].a;
    out.max = out.min;
    for (const Segment& s : out.segments) {
      out.min = out.min.cwiseMin(s.a).cwiseMin(s.b);
      out.max = out.max.cwiseMax(s.a).cwiseMax(s.b);
    }
  }
  return out;
}

namespace {

// A forgiving tokenizer: whitespace-separated numbers, with line numbers for errors.
class Tokens {
 public:
  explicit Tokens(std::string_view text) : text_(text) {}
  bool Next(double* value, std::string* error) {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
    if (pos_ >= text_.size()) {
      *error = "unexpected end of file at line " + std::to_string(line_);
      return false;
    }
    size_t end = pos_;
    while (end < text_.size() && !std::isspace(static_cast<unsigned char>(text_[end]))) ++end;
    const std::string_view token = text_.substr(pos_, end - pos_);
    const char* first = token.data();
    // from_chars rejects a leading '+'; accept it.
    if (!token.empty() && token[0] == '+') ++first;
    auto [ptr, ec] = std::from_chars(first, token.data() + token.size(), *value);
    if (ec != std::errc() || ptr != token.data() + token.size() || !std::isfinite(*value)) {
      *error = "line " + std::to_string(line_) + ": not a finite number: '" +
               std::string(token.substr(0, 40)) + "'";
      return false;
    }
    pos_ = end;
    return true;
  }
  bool AtEnd() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    return pos_ >= text_.size();
  }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  size_t line_ = 1;
};

}  // namespace

FloorPlanParse ParseTextFloorPlan(std::string_view text, std::string id) {
  FloorPlanParse out;
  Tokens tokens(text);
  double count_value = 0;
  if (!tokens.Next(&count_value, &out.error)) {
    out.error = "text floor plan: segment count missing: " + out.error;
    return out;
  }
  constexpr double kMaxSegments = 1e7;
  if (count_value < 1 || count_value > kMaxSegments || count_value != std::floor(count_value)) {
    out.error = "text floor plan: bad segment count " + std::to_string(count_value);
    return out;
  }
  const size_t count = static_cast<size_t>(count_value);
  std::vector<Segment> raw;
  raw.reserve(std::min<size_t>(count, 1 << 16));
  for (size_t i = 0; i < count; ++i) {
    double v[4];
    for (double& x : v) {
      if (!tokens.Next(&x, &out.error)) {
        out.error = "text floor plan: segment " + std::to_string(i + 1) + " of " +
                    std::to_string(count) + ": " + out.error;
        return out;
      }
    }
    raw.push_back({{v[0], v[1]}, {v[2], v[3]}});
  }
  if (!tokens.AtEnd()) {
    out.error = "text floor plan: more data after the " + std::to_string(count) + " segments";
    return out;
  }
  return MakeFloorPlan(std::move(id), std::move(raw));
}

uint64_t FloorPlanDigest(const FloorPlan& plan) {
  uint64_t h = 14695981039346656037ull;
  auto mix = [&](double v) {
    unsigned char bytes[sizeof v];
    std::memcpy(bytes, &v, sizeof v);
    for (unsigned char b : bytes) h = (h ^ b) * 1099511628211ull;
  };
  for (const Segment& s : plan.segments) {
    mix(s.a.x());
    mix(s.a.y());
    mix(s.b.x());
    mix(s.b.y());
  }
  return h;
}

namespace {

// Whether segments pq and s properly cross (touching ends do not count).
bool Crosses(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Segment& s) {
  auto side = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d u = a - o, v = b - o;
    return u.x() * v.y() - u.y() * v.x();
  };
  const double d1 = side(p, q, s.a), d2 = side(p, q, s.b);
  const double d3 = side(s.a, s.b, p), d4 = side(s.a, s.b, q);
  return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

// Whether the step p -> q meets segment s at least margin_m from both of its ends.
bool CrossingClearOfEnds(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Segment& s,
                         double margin_m) {
  const Eigen::Vector2d r = q - p, d = s.b - s.a;
  const double den = r.x() * d.y() - r.y() * d.x();
  if (den == 0) return false;
  const Eigen::Vector2d w = p - s.a;
  const double u = (w.x() * r.y() - w.y() * r.x()) / -den;  // along s, 0..1
  const double length = d.norm();
  return std::min(u, 1 - u) * length >= margin_m;
}

// Whether segment s lies wholly outside the box [lo, hi].
bool OutsideBox(const Segment& s, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  const Eigen::Vector2d smin = s.a.cwiseMin(s.b), smax = s.a.cwiseMax(s.b);
  return smax.x() < lo.x() || smin.x() > hi.x() || smax.y() < lo.y() || smin.y() > hi.y();
}

// The walls within pad_m of the box of a (non-empty) path.
std::vector<const Segment*> WallsNearPath(const std::vector<Eigen::Vector2d>& path,
                                          const FloorPlan& plan, double pad_m) {
  Eigen::Vector2d lo = path.front(), hi = path.front();
  for (const Eigen::Vector2d& p : path) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Eigen::Vector2d pad = Eigen::Vector2d::Constant(pad_m);
  std::vector<const Segment*> near;
  for (const Segment& s : plan.segments)
    if (!OutsideBox(s, lo - pad, hi + pad)) near.push_back(&s);
  return near;
}

// Whether the step p -> q crosses wall s, end_margin_m or more from its ends.
bool StepCrosses(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Segment& s,
                 double end_margin_m) {
  return !OutsideBox(s, p.cwiseMin(q), p.cwiseMax(q)) && Crosses(p, q, s) &&
         (end_margin_m <= 0 || CrossingClearOfEnds(p, q, s, end_margin_m));
}

}  // namespace

bool StepCrossesPlan(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const FloorPlan& plan,
                     double end_margin_m) {
  for (const Segment& s : plan.segments)
    if (StepCrosses(p, q, s, end_margin_m)) return true;
  return false;
}

std::vector<Eigen::Vector2d> PathOnPlan(const Se2& T_plan_slam,
                                        const std::vector<Eigen::Vector2d>& path_slam) {
  std::vector<Eigen::Vector2d> path_plan;
  path_plan.reserve(path_slam.size());
  for (const Eigen::Vector2d& p : path_slam)
    if (p.allFinite()) path_plan.push_back(T_plan_slam * p);
  return path_plan;
}

uint32_t PathCrossings(const std::vector<Eigen::Vector2d>& path, const FloorPlan& plan,
                       double end_margin_m) {
  if (path.size() < 2) return 0;
  // Only the walls in the path's box can be crossed: a few of a building's thousands.
  const std::vector<const Segment*> near = WallsNearPath(path, plan, 0);
  uint32_t crossings = 0;
  for (size_t i = 1; i < path.size(); ++i)
    for (const Segment* s : near)
      if (StepCrosses(path[i - 1], path[i], *s, end_margin_m)) {
        ++crossings;
        break;
      }
  return crossings;
}

namespace {

// Whether q is within reach of a position of the path (first), and whether one such
// position has a clear line of sight to it (second): no wall of `near` across the line,
// which stops standoff_m short of q so that q's own wall does not block it.
std::pair<bool, bool> InSight(const Eigen::Vector2d& q, const std::vector<Eigen::Vector2d>& path,
                              const std::vector<const Segment*>& near, double reach_m,
                              double standoff_m, double end_margin_m) {
  bool in_reach = false;
  for (const Eigen::Vector2d& v : path) {
    const Eigen::Vector2d d = q - v;
    const double n2 = d.squaredNorm();
    if (n2 > reach_m * reach_m) continue;
    in_reach = true;
    const double n = std::sqrt(n2);
    if (n <= standoff_m) return {true, true};
    const Eigen::Vector2d end = v + d * ((n - standoff_m) / n);
    if (std::none_of(near.begin(), near.end(),
                     [&](const Segment* s) { return StepCrosses(v, end, *s, end_margin_m); }))
      return {true, true};
  }
  return {in_reach, false};
}

}  // namespace

uint32_t HiddenPoints(const std::vector<Eigen::Vector2d>& points,
                      const std::vector<Eigen::Vector2d>& path, const FloorPlan& plan,
                      double reach_m, double standoff_m, double end_margin_m) {
  if (points.empty() || path.empty()) return 0;
  const std::vector<const Segment*> near = WallsNearPath(path, plan, reach_m);
  uint32_t hidden = 0;
  for (const Eigen::Vector2d& q : points) {
    const auto [in_reach, seen] = InSight(q, path, near, reach_m, standoff_m, end_margin_m);
    hidden += in_reach && !seen;
  }
  return hidden;
}

std::vector<Eigen::Vector2d> WallSamplesInSight(const std::vector<Eigen::Vector2d>& path,
                                                const FloorPlan& plan,
                                                const WallSampleOptions& options) {
  std::vector<Eigen::Vector2d> samples;
  if (path.empty() || !(options.reach_m > 0) || !(options.step_m > 0)) return samples;
  const std::vector<const Segment*> near = WallsNearPath(path, plan, options.reach_m);
  for (const Segment* s : near) {
    const double length = s->Length();
    const double steps = std::ceil(length / options.step_m);
    if (length < options.min_length_m || !(steps < 1e6)) continue;  // not a wall to walk past
    const int n = static_cast<int>(steps);
    for (int i = 0; i <= n; ++i) {
      const Eigen::Vector2d q = s->a + (s->b - s->a) * (n ? static_cast<double>(i) / n : 0.0);
      if (InSight(q, path, near, options.reach_m, options.standoff_m, options.end_margin_m).second)
        samples.push_back(q);
    }
  }
  return samples;
}

UnseenWalls CountUnseenWalls(const std::vector<Eigen::Vector2d>& points,
                             const std::vector<Eigen::Vector2d>& path, const FloorPlan& plan,
                             const UnseenWallsOptions& options) {
  UnseenWalls out;
  // The wall points in cells of match_m: a sample is explained by a point in its cell or
  // the eight around it (then within match_m, give or take the cell's diagonal).
  const double cell = std::max(options.match_m, 0.01);
  const auto key = [&](const Eigen::Vector2d& p) {
    return std::make_pair(static_cast<int64_t>(std::floor(p.x() / cell)),
                          static_cast<int64_t>(std::floor(p.y() / cell)));
  };
  std::set<std::pair<int64_t, int64_t>> occupied;
  for (const Eigen::Vector2d& p : points)
    if (p.allFinite() && p.cwiseAbs().maxCoeff() < 1e6) occupied.insert(key(p));
  for (const Eigen::Vector2d& q : WallSamplesInSight(path, plan, options.walls)) {
    ++out.expected;
    const auto [kx, ky] = key(q);
    bool seen = false;
    for (int64_t dy = -1; dy <= 1 && !seen; ++dy)
      for (int64_t dx = -1; dx <= 1 && !seen; ++dx) seen = occupied.count({kx + dx, ky + dy});
    out.missed += !seen;
  }
  return out;
}

}  // namespace floorpose
