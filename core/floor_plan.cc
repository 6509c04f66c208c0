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

const char* LineKindName(LineKind kind) {
  switch (kind) {
    case LineKind::kWall: return "wall";
    case LineKind::kWindow: return "window";
    case LineKind::kGlass: return "glass";
    case LineKind::kStairs: return "stairs";
    case LineKind::kElevator: return "elevator";
    case LineKind::kDoor: return "door";
    case LineKind::kExit: return "exit";
  }
  return "wall";
}

bool ParseLineKind(std::string_view name, LineKind* kind) {
  static constexpr std::pair<std::string_view, LineKind> kNames[] = {
      {"wall", LineKind::kWall},          {"window", LineKind::kWindow},
      {"glass", LineKind::kGlass},        {"glazing", LineKind::kGlass},
      {"curtain_wall", LineKind::kGlass}, {"stairs", LineKind::kStairs},
      {"stair", LineKind::kStairs},       {"staircase", LineKind::kStairs},
      {"elevator", LineKind::kElevator},  {"lift", LineKind::kElevator},
      {"door", LineKind::kDoor},          {"opening", LineKind::kDoor},
      {"exit", LineKind::kExit},          {"entrance", LineKind::kExit},
      {"emergency_exit", LineKind::kExit}};
  for (const auto& [n, k] : kNames)
    if (n == name) {
      *kind = k;
      return true;
    }
  return false;
}

FloorPlanParse MakeFloorPlan(std::string id, std::vector<Segment> raw) {
  std::vector<PlanLine> lines;
  lines.reserve(raw.size());
  for (const Segment& s : raw) lines.push_back({s, LineKind::kWall});
  return MakeFloorPlan(std::move(id), lines, {});
}

namespace {

// A door drawn on a wall (as IMDF's openings lie on its units' outlines, or a CAD door
// over the wall line) is a gap in it, and a window or glass drawn on one replaces that
// part of it: walls lose what those lines cover, where one runs along a wall within 3
// degrees and 5 cm.
std::vector<PlanLine> CutOpenings(const std::vector<PlanLine>& lines) {
  std::vector<const Segment*> openings;
  for (const PlanLine& l : lines)
    if (IsOpening(l.kind) || l.kind == LineKind::kWindow || l.kind == LineKind::kGlass)
      openings.push_back(&l.segment);
  if (openings.empty()) return lines;
  constexpr double kAlongRad = 3.0 * M_PI / 180, kOffM = 0.05;
  std::vector<PlanLine> out;
  for (const PlanLine& l : lines) {
    const Segment& s = l.segment;
    const double length = s.Length();
    if (l.kind != LineKind::kWall || !(length > 0)) {
      out.push_back(l);
      continue;
    }
    const Eigen::Vector2d d = (s.b - s.a) / length, n(-d.y(), d.x());
    std::vector<std::pair<double, double>> cuts;  // along s, metres from a
    for (const Segment* o : openings) {
      const Eigen::Vector2d od = o->b - o->a;
      if (std::abs(n.dot(o->a - s.a)) > kOffM || std::abs(n.dot(o->b - s.a)) > kOffM ||
          std::abs(n.dot(od)) > std::sin(kAlongRad) * od.norm())
        continue;
      const double t0 = d.dot(o->a - s.a), t1 = d.dot(o->b - s.a);
      const double lo = std::max(0.0, std::min(t0, t1)), hi = std::min(length, std::max(t0, t1));
      if (hi > lo) cuts.emplace_back(lo, hi);
    }
    if (cuts.empty()) {
      out.push_back(l);
      continue;
    }
    std::sort(cuts.begin(), cuts.end());
    double from = 0;
    for (const auto& [lo, hi] : cuts) {
      if (lo > from) out.push_back({{s.a + from * d, s.a + lo * d}, l.kind});
      from = std::max(from, hi);
    }
    if (from < length) out.push_back({{s.a + from * d, s.b}, l.kind});
  }
  return out;
}

}  // namespace

FloorPlanParse MakeFloorPlan(std::string id, const std::vector<PlanLine>& drawn,
                             std::vector<PlanRoom> rooms) {
  const std::vector<PlanLine> lines = CutOpenings(drawn);
  FloorPlanParse out;
  out.plan.id = std::move(id);
  out.plan.rooms = std::move(rooms);
  // Duplicates are found on endpoints rounded to 1 mm, in either direction, among the
  // barriers and among the openings.
  std::set<std::tuple<bool, long long, long long, long long, long long>> seen;
  auto mm = [](double v) { return std::llround(v * 1000.0); };
  bool mixed = false;
  for (const PlanLine& line : lines) {
    const Segment& s = line.segment;
    if (!s.a.allFinite() || !s.b.allFinite() || s.Length() < 1e-3) {
      ++out.dropped_segments;
      continue;
    }
    const bool opening = IsOpening(line.kind);
    auto key = std::make_tuple(opening, mm(s.a.x()), mm(s.a.y()), mm(s.b.x()), mm(s.b.y()));
    auto rev = std::make_tuple(opening, mm(s.b.x()), mm(s.b.y()), mm(s.a.x()), mm(s.a.y()));
    if (seen.count(key) || seen.count(rev)) {
      ++out.dropped_segments;
      continue;
    }
    seen.insert(key);
    if (opening) {
      out.plan.openings.push_back(line);
      continue;
    }
    out.plan.segments.push_back(s);
    out.plan.kinds.push_back(line.kind);
    mixed |= line.kind != LineKind::kWall;
  }
  if (!mixed) out.plan.kinds.clear();  // all walls
  if (out.plan.segments.empty()) {
    out.error = "floor plan has no usable wall segments";
    return out;
  }
  Eigen::Vector2d lo = out.plan.segments[0].a, hi = lo;
  auto grow = [&](const Segment& s) {
    lo = lo.cwiseMin(s.a).cwiseMin(s.b);
    hi = hi.cwiseMax(s.a).cwiseMax(s.b);
  };
  for (const Segment& s : out.plan.segments) grow(s);
  for (const PlanLine& o : out.plan.openings) grow(o.segment);
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
    if (!plan.kinds.empty()) out.kinds.push_back(plan.KindOf(&s - plan.segments.data()));
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
  // A plan of walls alone keeps the digest it had before plans had kinds.
  for (LineKind k : plan.kinds) h = (h ^ static_cast<uint8_t>(k)) * 1099511628211ull;
  for (const PlanLine& o : plan.openings) {
    h = (h ^ static_cast<uint8_t>(o.kind)) * 1099511628211ull;
    for (double v : {o.segment.a.x(), o.segment.a.y(), o.segment.b.x(), o.segment.b.y()}) mix(v);
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

// The barriers within pad_m of the box of a (non-empty) path; with meshed_only, those a
// headset meshes (IsMeshed): it sees through glass and windows.
std::vector<const Segment*> WallsNearPath(const std::vector<Eigen::Vector2d>& path,
                                          const FloorPlan& plan, double pad_m,
                                          bool meshed_only = false) {
  Eigen::Vector2d lo = path.front(), hi = path.front();
  for (const Eigen::Vector2d& p : path) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Eigen::Vector2d pad = Eigen::Vector2d::Constant(pad_m);
  std::vector<const Segment*> near;
  for (size_t i = 0; i < plan.segments.size(); ++i)
    if (!OutsideBox(plan.segments[i], lo - pad, hi + pad) &&
        (!meshed_only || IsMeshed(plan.KindOf(i))))
      near.push_back(&plan.segments[i]);
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
  const std::vector<const Segment*> near = WallsNearPath(path, plan, reach_m, true);
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
  const std::vector<const Segment*> near = WallsNearPath(path, plan, options.reach_m, true);
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
