#include "core/sim/simulator.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <tuple>
#include <utility>

#include "core/random.h"
#include "core/sim/free_space.h"

namespace floorpose::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

// One random stream per concern (reality, walk, drift, sensor, mesh, pick), so that, e.g.,
// turning the mesh off leaves the walk and the drift as they were.
SplitMix64 Stream(uint64_t seed, uint64_t salt) {
  SplitMix64 mix(seed ^ (0xd1b54a32d192ed03ULL * (salt + 1)));
  return SplitMix64(mix.Next());
}

// A planar rectangle of reality: origin + a u + b v for a in [0, u_len], b in [0, v_len],
// with u, v unit and orthogonal. Seen in nu x nv patches.
struct Surface {
  Eigen::Vector3d origin, u, v, normal;
  double u_len = 0.0, v_len = 0.0;
  int nu = 1, nv = 1;
  Eigen::Vector2d centre;  // horizontal bounding circle, to skip far surfaces quickly
  double radius = 0.0;
  int segment = -1;  // the plan wall it is, or -1 (not on the plan)

  // The horizontal centre of patch (iu, iv).
  Eigen::Vector2d PatchCentre(int iu, int iv) const {
    return (origin + (iu + 0.5) * u_len / nu * u + (iv + 0.5) * v_len / nv * v).head<2>();
  }
};

Surface MakeSurface(const Eigen::Vector3d& origin, const Eigen::Vector3d& u_edge,
                    const Eigen::Vector3d& v_edge, double patch_m) {
  Surface s;
  s.origin = origin;
  s.u_len = u_edge.norm();
  s.v_len = v_edge.norm();
  s.u = u_edge / s.u_len;
  s.v = v_edge / s.v_len;
  s.normal = s.u.cross(s.v).normalized();
  s.nu = std::max(1, static_cast<int>(std::ceil(s.u_len / patch_m - 1e-9)));
  s.nv = std::max(1, static_cast<int>(std::ceil(s.v_len / patch_m - 1e-9)));
  const Eigen::Vector3d c = origin + 0.5 * (u_edge + v_edge);
  s.centre = c.head<2>();
  s.radius = 0.5 * (u_edge + v_edge).head<2>().norm() + 0.5 * (u_edge - v_edge).head<2>().norm();
  return s;
}

// Patches: of a surface (surface >= 0, iu, iv), of the floor (-1) or the ceiling (-2)
// (iu, iv = cell indices).
constexpr int kFloor = -1, kCeiling = -2;
using PatchKey = std::tuple<int, int, int>;
using ChunkKey = std::pair<int, int>;

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

bool SegmentsIntersect(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                       const Eigen::Vector2d& d) {
  const double d1 = Cross(b - a, c - a), d2 = Cross(b - a, d - a);
  const double d3 = Cross(d - c, a - c), d4 = Cross(d - c, b - c);
  return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0));
}

bool PolygonsOverlap(const std::vector<Eigen::Vector2d>& p, const std::vector<Eigen::Vector2d>& q) {
  for (size_t i = 0, j = p.size() - 1; i < p.size(); j = i++)
    for (size_t k = 0, l = q.size() - 1; k < q.size(); l = k++)
      if (SegmentsIntersect(p[j], p[i], q[l], q[k])) return true;
  return InsidePolygon(p, q[0]) || InsidePolygon(q, p[0]);
}

// A rectangle centred at c, `length` along yaw and `width` across.
std::vector<Eigen::Vector2d> Rectangle(const Eigen::Vector2d& c, double yaw, double length,
                                       double width) {
  const Eigen::Vector2d u(std::cos(yaw), std::sin(yaw)), v(-u.y(), u.x());
  const Eigen::Vector2d a = 0.5 * length * u, b = 0.5 * width * v;
  return {c - a - b, c + a - b, c + a + b, c - a + b};
}

// The segments drawing the same physical wall as segment i: i itself, the other face of a
// thick wall (parallel, within 0.5 m, overlapping) and the short caps joining the faces.
// Absent or glass walls lose both faces, as they would in a building.
std::vector<size_t> WallGroup(const FloorPlan& plan, size_t i) {
  const Segment& s = plan.segments[i];
  const Eigen::Vector2d dir = (s.b - s.a).normalized();
  std::vector<size_t> group{i};
  for (size_t j = 0; j < plan.segments.size(); ++j) {
    const Segment& o = plan.segments[j];
    if (j == i || o.Length() < 1e-6) continue;
    const Eigen::Vector2d odir = (o.b - o.a).normalized();
    if (std::abs(Cross(dir, odir)) > std::sin(5 * kDeg)) continue;
    if (std::abs(Cross(dir, 0.5 * (o.a + o.b) - s.a)) > 0.5) continue;
    const double t0 = (o.a - s.a).dot(dir), t1 = (o.b - s.a).dot(dir);
    const double overlap = std::min(std::max(t0, t1), s.Length()) - std::max(std::min(t0, t1), 0.0);
    if (overlap > 0.5 * std::min(s.Length(), o.Length())) group.push_back(j);
  }
  const size_t faces = group.size();
  for (size_t j = 0; j < plan.segments.size(); ++j) {
    const Segment& o = plan.segments[j];
    if (o.Length() > 0.5 || std::find(group.begin(), group.end(), j) != group.end()) continue;
    auto near_end = [&](const Eigen::Vector2d& p) {
      for (size_t k = 0; k < faces; ++k) {
        const Segment& f = plan.segments[group[k]];
        if ((f.a - p).norm() < 0.05 || (f.b - p).norm() < 0.05) return true;
      }
      return false;
    };
    if (near_end(o.a) && near_end(o.b)) group.push_back(j);
  }
  return group;
}

// Random order of 0..n-1 (Fisher-Yates).
std::vector<size_t> Shuffled(size_t n, SplitMix64& rng) {
  std::vector<size_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = i;
  for (size_t i = n; i > 1; --i) std::swap(order[i - 1], order[rng.Next() % i]);
  return order;
}

double NearestWallDirection(const FloorPlan& plan, const Eigen::Vector2d& p) {
  double best = 1e300, yaw = 0.0;
  for (const Segment& s : plan.segments) {
    const double d = (ClosestPointOnSegment(s, p) - p).norm();
    if (d < best && s.Length() > 0.3)
      best = d, yaw = std::atan2(s.b.y() - s.a.y(), s.b.x() - s.a.x());
  }
  return yaw;
}

std::string Format(const char* format, double a = 0, double b = 0, double c = 0, double d = 0) {
  char text[256];
  std::snprintf(text, sizeof(text), format, a, b, c, d);
  return text;
}

// Where the ray from p along unit u first meets a segment of the plan other than `skip`,
// within [min_m, max_m]: a proper crossing, or the end of a wall lying on the ray's line
// (a face cut by an opening). Infinity when none.
double RayHit(const FloorPlan& plan, size_t skip, const Eigen::Vector2d& p,
              const Eigen::Vector2d& u, double min_m, double max_m) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t j = 0; j < plan.segments.size(); ++j) {
    if (j == skip) continue;
    const Segment& o = plan.segments[j];
    const Eigen::Vector2d d = o.b - o.a;
    const double denom = Cross(u, d);
    if (std::abs(denom) > 1e-9) {
      const double t = Cross(o.a - p, d) / denom, s = Cross(o.a - p, u) / denom;
      if (s >= -1e-6 && s <= 1 + 1e-6 && t >= min_m && t <= max_m) best = std::min(best, t);
      continue;
    }
    for (const Eigen::Vector2d& e : {o.a, o.b}) {  // parallel: its nearer end on the line
      const double t = (e - p).dot(u);
      if (std::abs(Cross(u, e - p)) < 0.02 && t >= min_m && t <= max_m) best = std::min(best, t);
    }
  }
  return best;
}

// The plan's openings up to max_m wide drawn closed: from each wall's end along its own
// line to the next wall that line meets, 0.6 to max_m on (a door between two walls, once
// in each face of a thick wall), unless something already stands in the gap.
std::vector<Segment> DoorLines(const FloorPlan& plan, double max_m) {
  constexpr double kMinDoor = 0.6;
  std::vector<Segment> out;
  std::set<std::tuple<long long, long long, long long, long long>> seen;
  auto cm = [](double v) { return std::llround(v * 100.0); };
  for (size_t i = 0; i < plan.segments.size(); ++i) {
    const Segment& s = plan.segments[i];
    if (s.Length() < 0.3) continue;  // caps and jambs: the faces close their doors
    for (const auto& [p, q] : {std::pair{s.a, s.b}, std::pair{s.b, s.a}}) {
      const Eigen::Vector2d u = (p - q).normalized();
      const double t = RayHit(plan, i, p, u, kMinDoor, max_m);
      if (!std::isfinite(t)) continue;
      const Eigen::Vector2d e = p + t * u;
      if (StepCrossesPlan(p + 0.01 * u, e - 0.01 * u, plan)) continue;
      bool covered = false;  // a wall already lies along the gap
      for (const Segment& o : plan.segments)
        covered =
            covered || (ClosestPointOnSegment(o, 0.5 * (p + e)) - 0.5 * (p + e)).norm() < 0.02;
      if (covered) continue;
      auto key = std::make_tuple(cm(p.x()), cm(p.y()), cm(e.x()), cm(e.y()));
      if (std::get<0>(key) > std::get<2>(key) ||
          (std::get<0>(key) == std::get<2>(key) && std::get<1>(key) > std::get<3>(key)))
        key = std::make_tuple(cm(e.x()), cm(e.y()), cm(p.x()), cm(p.y()));
      if (seen.insert(key).second) out.push_back({p, e});
    }
  }
  return out;
}

// Whether a wall (its faces) is on the building's outside: a ray across one of its faces
// of 1 m or more, from its middle, leaves the plan without meeting another wall.
bool ExteriorWall(const FloorPlan& plan, const std::vector<size_t>& group) {
  const double reach = (plan.max - plan.min).norm() + 1.0;
  for (size_t i : group) {
    const Segment& s = plan.segments[i];
    if (s.Length() < 1.0) continue;
    for (double side : {1.0, -1.0}) {
      const Eigen::Vector2d n = side * s.Normal();
      if (!std::isfinite(RayHit(plan, i, 0.5 * (s.a + s.b) + 0.01 * n, n, 0.0, reach))) return true;
    }
  }
  return false;
}

// The walls reality has: plan walls present (moved where reality moved them), glass too.
std::vector<Segment> StandingWalls(const FloorPlan& plan, const Reality& reality) {
  std::vector<Segment> out;
  for (size_t i = 0; i < plan.segments.size(); ++i)
    if (reality.plan_wall_present[i])
      out.push_back({plan.segments[i].a + reality.plan_wall_offset[i],
                     plan.segments[i].b + reality.plan_wall_offset[i]});
  return out;
}

// Scenario stale: the building was changed after the plan was drawn. Of the interior walls
// (1 m or longer, whole: both faces and caps), about gone_share of their length is gone
// and moved_share stands min_move_m to max_move_m across from where it is drawn.
std::string MarkStale(const FloorPlan& plan, const SimulatorOptions& o, SplitMix64& rng,
                      Reality* reality) {
  std::vector<std::vector<size_t>> interior;
  std::vector<uint8_t> grouped(plan.segments.size(), 0);
  double total = 0.0;
  for (size_t i : Shuffled(plan.segments.size(), rng)) {
    if (grouped[i] || plan.segments[i].Length() < 1.0) continue;
    std::vector<size_t> group;
    for (size_t j : WallGroup(plan, i))
      if (!grouped[j]) group.push_back(j), grouped[j] = 1;
    if (ExteriorWall(plan, group)) continue;
    for (size_t j : group) total += plan.segments[j].Length();
    interior.push_back(std::move(group));
  }
  double gone = 0.0, moved = 0.0;
  for (const std::vector<size_t>& group : interior) {
    double length = 0.0;
    for (size_t j : group) length += plan.segments[j].Length();
    if (gone < o.stale_gone_share * total) {
      for (size_t j : group) reality->plan_wall_present[j] = 0;
      gone += length;
    } else if (moved < o.stale_moved_share * total) {
      const double distance = rng.Uniform(o.min_move_m, o.max_move_m);
      const double side = rng.Next() % 2 ? 1.0 : -1.0;
      const Eigen::Vector2d offset = distance * side * plan.segments[group.front()].Normal();
      for (size_t j : group) reality->plan_wall_offset[j] = offset;
      moved += length;
    }
  }
  return Format("stale: of %.0f m of interior walls on the plan, %.0f%% are gone and %.0f%% ",
                total, total > 0 ? 100.0 * gone / total : 0.0,
                total > 0 ? 100.0 * moved / total : 0.0) +
         Format("stand %.1f-%.1f m from where they are drawn", o.min_move_m, o.max_move_m);
}

// ---------------------------------------------------------------------------------------
// Reality: the plan's walls as they are in the scenario, plus what the plan does not show.

class RealityBuilder {
 public:
  RealityBuilder(const FloorPlan& plan, FreeSpace& free_space,
                 const std::vector<Eigen::Vector2d>& keep_clear, SplitMix64& rng, Reality initial)
      : reality(std::move(initial)),
        plan_(plan),
        free_space_(free_space),
        keep_clear_(keep_clear),
        rng_(rng) {}

  double TotalWallLength() const {
    double total = 0.0;
    for (const Segment& s : plan_.segments) total += s.Length();
    return total;
  }

  // Marks whole walls (both faces) among those of length [min_m, max_m], in random order,
  // until `share` of the total wall length is marked. Returns the marked length.
  double MarkWalls(std::vector<uint8_t>* marks, double share, double min_m, double max_m) {
    const double goal = share * TotalWallLength();
    double marked = 0.0;
    for (size_t i : Shuffled(plan_.segments.size(), rng_)) {
      if (marked >= goal) break;
      const double length = plan_.segments[i].Length();
      if ((*marks)[i] || length < min_m || length > max_m) continue;
      for (size_t j : WallGroup(plan_, i)) {
        if ((*marks)[j]) continue;
        (*marks)[j] = 1;
        marked += plan_.segments[j].Length();
      }
    }
    return marked;
  }

  // Puts an object (or wall) not on the plan on the floor, unless it would stand in a plan
  // wall or another object, on the given trajectory, or cut the walkable region apart.
  bool Place(std::vector<Eigen::Vector2d> footprint, double height, const char* kind) {
    // Walls as drawn, and where moved walls stand.
    auto blocks = [&](const Segment& s) {
      if (InsidePolygon(footprint, s.a) || InsidePolygon(footprint, s.b)) return true;
      for (size_t i = 0, j = footprint.size() - 1; i < footprint.size(); j = i++)
        if (SegmentsIntersect(footprint[j], footprint[i], s.a, s.b)) return true;
      return false;
    };
    for (size_t i = 0; i < plan_.segments.size(); ++i) {
      const Segment& s = plan_.segments[i];
      const Eigen::Vector2d& offset = reality.plan_wall_offset[i];
      if (blocks(s) || (!offset.isZero() && blocks({s.a + offset, s.b + offset}))) return false;
    }
    for (const Reality::Prism& e : reality.extras)
      if (PolygonsOverlap(footprint, e.footprint)) return false;
    for (const Eigen::Vector2d& p : keep_clear_)
      if (DistanceToPolygon(footprint, p) < free_space_.options().body_radius_m) return false;
    if (!free_space_.BlockIfConnected(footprint)) return false;
    reality.extras.push_back({std::move(footprint), height, kind});
    return true;
  }

  // A random walkable point with at least this clearance (or the last one tried).
  Eigen::Vector2d RandomFreePoint(double min_clearance_m) {
    const std::vector<int>& cells = free_space_.cells();
    Eigen::Vector2d p = free_space_.CellCentre(cells[rng_.Next() % cells.size()]);
    for (int i = 0; i < 20 && free_space_.Clearance(p) < min_clearance_m; ++i)
      p = free_space_.CellCentre(cells[rng_.Next() % cells.size()]);
    return p;
  }

  // Placed count of `count` objects made by `make`, a few tries each.
  template <typename Make>
  int PlaceMany(int count, Make make) {
    int placed = 0;
    for (int i = 0; i < count; ++i)
      for (int attempt = 0; attempt < 6 && !free_space_.empty(); ++attempt)
        if (make()) {
          ++placed;
          break;
        }
    return placed;
  }

  double AlignedYaw(const Eigen::Vector2d& p) {
    return NearestWallDirection(plan_, p) + 0.5 * M_PI * static_cast<double>(rng_.Next() % 4);
  }

  // Office furniture and people (thesis section 7.7: the hall "filled with tables").
  std::string Furnish() {
    const double area = free_space_.walkable_area_m2();
    const int desks = PlaceMany(std::min(200, static_cast<int>(area / 15)), [&] {
      const Eigen::Vector2d c = RandomFreePoint(0.9);
      return Place(Rectangle(c, AlignedYaw(c), 1.6, 0.8), 0.75, "desk");
    });
    // Cabinets: their back against a wall, on the side of the wall one can walk on.
    std::vector<double> cumulative;
    double total = 0.0;
    for (const Segment& s : plan_.segments) cumulative.push_back(total += s.Length());
    const int cabinets = PlaceMany(std::min(120, static_cast<int>(area / 25)), [&] {
      const double pick = rng_.Uniform(0.0, total);
      const size_t i =
          std::lower_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin();
      const Segment& s = plan_.segments[std::min(i, plan_.segments.size() - 1)];
      if (s.Length() < 1.4) return false;
      const Eigen::Vector2d dir = (s.b - s.a).normalized();
      Eigen::Vector2d n = s.Normal();
      const Eigen::Vector2d at = s.a + dir * rng_.Uniform(0.7, s.Length() - 0.7);
      if (!free_space_.Walkable(at + 0.8 * n)) n = -n;
      if (!free_space_.Walkable(at + 0.8 * n)) return false;  // not a wall of a room we walk
      return Place(Rectangle(at + n * 0.28, std::atan2(dir.y(), dir.x()), 1.2, 0.5), 2.0,
                   "cabinet");
    });
    const int people = PlaceMany(std::min(60, static_cast<int>(area / 40)), [&] {
      const Eigen::Vector2d c = RandomFreePoint(0.5);
      return Place(Rectangle(c, rng_.Uniform(0, M_PI), 0.4, 0.4), 1.8, "person");
    });
    return Format(
        "office: %.0f desks (1.6x0.8x0.75 m), %.0f cabinets (1.2x0.5x2.0 m, against "
        "walls), %.0f people (0.4x0.4x1.8 m), none on the plan",
        desks, cabinets, people);
  }

  // Thesis section 7.7: walls on the plan that are not there (fire doors), a round object
  // in the middle of a space, walls that are not on the plan.
  std::string Mismatch(double share, double ceiling) {
    const double absent = MarkWalls(&absent_marks_, share, 1.0, 15.0);
    for (size_t i = 0; i < absent_marks_.size(); ++i)
      if (absent_marks_[i]) reality.plan_wall_present[i] = 0;
    const double area = free_space_.walkable_area_m2();
    const int walls = PlaceWalls(ceiling);
    const int pillars = PlaceMany(std::min(10, static_cast<int>(area / 200)), [&] {
      const Eigen::Vector2d c = RandomFreePoint(1.2);
      const double r = rng_.Uniform(0.3, 0.8);
      std::vector<Eigen::Vector2d> octagon;
      for (int k = 0; k < 8; ++k)
        octagon.push_back(c + r * Eigen::Vector2d(std::cos(k * M_PI / 4), std::sin(k * M_PI / 4)));
      return Place(octagon, ceiling, "pillar");
    });
    const int boxes = PlaceMany(std::min(20, static_cast<int>(area / 100)), [&] {
      const Eigen::Vector2d c = RandomFreePoint(0.9);
      return Place(Rectangle(c, AlignedYaw(c), rng_.Uniform(0.6, 2.0), rng_.Uniform(0.6, 1.5)),
                   rng_.Uniform(0.8, 2.0), "box");
    });
    return Format(
        "mismatch: %.0f%% of the wall length on the plan is absent; not on the plan: "
        "%.0f walls (1.5-4 m), %.0f round pillars, %.0f boxes",
        100.0 * absent / TotalWallLength(), walls, pillars, boxes);
  }

  // New walls where the plan has none (stale), as many as the mismatch scenario's.
  std::string NewWalls(double ceiling) {
    return Format("; %.0f new walls (1.5-4 m) not on the plan", PlaceWalls(ceiling));
  }

  // Walls of 1.5-4 m that are not on the plan, one per 60 m2 of walkable floor (at most 40).
  int PlaceWalls(double ceiling) {
    const double area = free_space_.walkable_area_m2();
    return PlaceMany(std::min(40, static_cast<int>(area / 60)), [&] {
      const Eigen::Vector2d c = RandomFreePoint(0.6);
      return Place(Rectangle(c, AlignedYaw(c), rng_.Uniform(1.5, 4.0), 0.12), ceiling, "wall");
    });
  }

  std::string Glass(double share) {
    const double glass = MarkWalls(&reality.plan_wall_glass, share, 2.0, 1e9);
    return Format(
        "glass: %.0f%% of the wall length (walls of 2 m or more) is glass, invisible to "
        "the sensor",
        100.0 * glass / TotalWallLength());
  }

  Reality reality;

 private:
  const FloorPlan& plan_;
  FreeSpace& free_space_;
  const std::vector<Eigen::Vector2d>& keep_clear_;
  SplitMix64& rng_;
  std::vector<uint8_t> absent_marks_ = std::vector<uint8_t>(plan_.segments.size(), 0);
};

std::vector<Surface> RealSurfaces(const FloorPlan& plan, const Reality& reality, double patch_m) {
  std::vector<Surface> out;
  const Eigen::Vector3d up(0, 0, reality.ceiling_m);
  for (size_t i = 0; i < plan.segments.size(); ++i) {
    const Segment& s = plan.segments[i];
    if (!reality.plan_wall_present[i] || reality.plan_wall_glass[i] || s.Length() < 1e-3) continue;
    const Eigen::Vector2d a = s.a + reality.plan_wall_offset[i];
    out.push_back(
        MakeSurface({a.x(), a.y(), 0.0}, {s.b.x() - s.a.x(), s.b.y() - s.a.y(), 0.0}, up, patch_m));
    out.back().segment = reality.plan_wall_offset[i].isZero() ? static_cast<int>(i) : -1;
  }
  for (const Reality::Prism& p : reality.extras) {
    const auto& f = p.footprint;
    for (size_t i = 0; i < f.size(); ++i) {
      const Eigen::Vector2d& a = f[i];
      const Eigen::Vector2d& b = f[(i + 1) % f.size()];
      out.push_back(MakeSurface({a.x(), a.y(), 0.0}, {b.x() - a.x(), b.y() - a.y(), 0.0},
                                {0, 0, p.height_m}, patch_m));
    }
    if (f.size() == 4 && p.height_m < reality.ceiling_m - 0.05)  // the top of a box
      out.push_back(MakeSurface({f[0].x(), f[0].y(), p.height_m},
                                {f[1].x() - f[0].x(), f[1].y() - f[0].y(), 0.0},
                                {f[3].x() - f[0].x(), f[3].y() - f[0].y(), 0.0}, patch_m));
  }
  return out;
}

// A loss of tracking (relocalize): the steps [from, to) send nothing, and the SLAM frame
// jumps at step `to` by `angle` and `offset` about where the headset is.
struct Loss {
  size_t from = 0, to = 0;
  double angle = 0.0;
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();
};

// min_losses..max_losses losses over a walk of n steps, after the wall pick: one in each
// of that many equal slots, none where a slot is too short to hold one.
std::vector<Loss> DrawLosses(size_t n, const SimulatorOptions& o, SplitMix64& rng) {
  std::vector<Loss> losses;
  const double dt = o.pose_period_s;
  const int count = o.min_losses + static_cast<int>(rng.Next() % (o.max_losses - o.min_losses + 1));
  const double begin_s = o.pick_time_s + 10.0, end_s = (n - 1) * dt - 5.0;
  const double slot = (end_s - begin_s) / count;
  for (int k = 0; k < count && slot >= o.min_loss_s + 1.0; ++k) {
    const double duration = std::min(rng.Uniform(o.min_loss_s, o.max_loss_s), slot - 1.0);
    const double start = begin_s + k * slot + rng.Uniform(0.0, slot - duration);
    Loss loss;
    loss.from = static_cast<size_t>(std::ceil(start / dt));
    loss.to = std::min(n - 1, loss.from + static_cast<size_t>(std::llround(duration / dt)));
    loss.angle = rng.Uniform(-o.max_jump_rad, o.max_jump_rad);
    const double direction = rng.Uniform(-M_PI, M_PI);
    loss.offset =
        rng.Uniform(0.0, o.max_jump_m) * Eigen::Vector2d(std::cos(direction), std::sin(direction));
    losses.push_back(loss);
  }
  return losses;
}

// The steps sent while tracking was lost go; the pick keeps its step.
void DropLostSteps(const std::vector<uint8_t>& lost, Simulation* sim) {
  std::vector<SimulatedStep> kept;
  size_t pick_step = 0;
  for (size_t i = 0; i < sim->steps.size(); ++i) {
    if (lost[i]) continue;
    if (i == sim->pick_step) pick_step = kept.size();
    kept.push_back(std::move(sim->steps[i]));
  }
  sim->steps = std::move(kept);
  sim->pick_step = pick_step;
}

// The plan scanned from paper (scaled): the drawn plan, the truth and the pick's plan side
// scaled 1-2% per axis and skewed about the input's centre, as a commander reads them off
// that plan. Returns the description.
std::string ScaleAndSkew(const FloorPlan& input, const SimulatorOptions& o, SplitMix64& rng,
                         Simulation* sim) {
  auto error = [&] {  // the sign, then the size (in this order, for every compiler)
    const double sign = rng.Next() % 2 ? 1.0 : -1.0;
    return sign * rng.Uniform(o.min_scale_error, o.max_scale_error);
  };
  const double sx = 1.0 + error(), sy = 1.0 + error();
  const double skew = rng.Uniform(-o.max_skew_rad, o.max_skew_rad);
  Eigen::Matrix2d A;
  A << sx, sx * std::tan(skew), 0.0, sy;
  sim->plan_from_reality = A;
  const Eigen::Vector2d c = 0.5 * (input.min + input.max);
  auto to_plan = [&](const Eigen::Vector2d& p) -> Eigen::Vector2d { return c + A * (p - c); };
  FloorPlan& plan = sim->plan;
  plan.min = plan.max = to_plan(input.segments.front().a);
  for (Segment& seg : plan.segments) {
    seg = {to_plan(seg.a), to_plan(seg.b)};
    plan.min = plan.min.cwiseMin(seg.a).cwiseMin(seg.b);
    plan.max = plan.max.cwiseMax(seg.a).cwiseMax(seg.b);
  }
  for (SimulatedStep& step : sim->steps) {
    const double h = step.true_plan.heading;
    const Eigen::Vector2d d = A * Eigen::Vector2d(std::cos(h), std::sin(h));
    step.true_plan.position = to_plan(step.true_plan.position);
    step.true_plan.heading = std::atan2(d.y(), d.x());
  }
  sim->pick.plan_point = to_plan(sim->pick.plan_point);
  sim->pick.plan_normal = (A.inverse().transpose() * sim->pick.plan_normal).normalized();
  return Format(
      "The plan is scaled %+.2f%% along x and %+.2f%% along y and skewed %.2f deg about its "
      "centre. ",
      100.0 * (sx - 1.0), 100.0 * (sy - 1.0), skew / kDeg);
}

// ---------------------------------------------------------------------------------------
// The walk.

struct HeadSample {
  Eigen::Vector2d position;
  double yaw = 0.0;    // viewing direction
  double pitch = 0.0;  // up positive
};

// A polyline walked at constant speed.
struct Leg {
  std::vector<Eigen::Vector2d> points;
  std::vector<double> along;  // cumulative length at each point
  double speed = 1.0;
  double Length() const { return along.back(); }
  Eigen::Vector2d At(double s) const {
    s = std::clamp(s, 0.0, Length());
    size_t i = std::upper_bound(along.begin(), along.end(), s) - along.begin();
    i = std::clamp<size_t>(i, 1, points.size() - 1);
    const double span = along[i] - along[i - 1];
    const double f = span > 0 ? (s - along[i - 1]) / span : 1.0;
    return points[i - 1] + f * (points[i] - points[i - 1]);
  }
};

Leg MakeLeg(std::vector<Eigen::Vector2d> points, double speed) {
  Leg leg;
  leg.points = std::move(points);
  leg.speed = speed;
  leg.along.push_back(0.0);
  for (size_t i = 1; i < leg.points.size(); ++i)
    leg.along.push_back(leg.along.back() + (leg.points[i] - leg.points[i - 1]).norm());
  return leg;
}

// The head's motion on top of the body's heading: looking around while walking (two
// sines) and the pitch swinging; random phases per walk.
class HeadSwing {
 public:
  explicit HeadSwing(SplitMix64& rng)
      : phase1_(rng.Uniform(0, 2 * M_PI)),
        phase2_(rng.Uniform(0, 2 * M_PI)),
        phase3_(rng.Uniform(0, 2 * M_PI)) {}
  double Look(double t, const SimulatorOptions& o) const {
    return o.look_around_rad * (0.7 * std::sin(2 * M_PI * t / 5.3 + phase1_) +
                                0.3 * std::sin(2 * M_PI * t / 2.1 + phase2_));
  }
  double Pitch(double t, const SimulatorOptions& o) const {
    return o.head_pitch_rad + o.head_pitch_swing_rad * std::sin(2 * M_PI * t / 7.7 + phase3_);
  }

 private:
  double phase1_, phase2_, phase3_;
};

// Goals: random places, not too close. Of a few candidates, the corridor scenario takes
// the farthest from here, so that the walk strings long hallways together; the others the
// farthest from every goal so far, so that the walk explores the building (uniform goals
// alone would keep returning to its largest room).
class GoalChooser {
 public:
  GoalChooser(const FreeSpace& fs, Scenario scenario, double min_goal_distance_m, SplitMix64& rng)
      : fs_(fs), scenario_(scenario), min_goal_distance_m_(min_goal_distance_m), rng_(rng) {}

  // A random free cell's centre, tried a few times for min_clearance from the walls.
  Eigen::Vector2d RandomPoint(double min_clearance) {
    const std::vector<int>& cells = fs_.cells();
    Eigen::Vector2d p = fs_.CellCentre(cells[rng_.Next() % cells.size()]);
    for (int i = 0; i < 20 && fs_.Clearance(p) < min_clearance; ++i)
      p = fs_.CellCentre(cells[rng_.Next() % cells.size()]);
    return p;
  }
  // Where the walk starts: a goal visited.
  Eigen::Vector2d Start() {
    const Eigen::Vector2d p = RandomPoint(0.5);
    visited_.push_back(p);
    return p;
  }
  Eigen::Vector2d Next(const Eigen::Vector2d& from) {
    auto score = [&](const Eigen::Vector2d& p) {
      if (scenario_ == Scenario::kCorridor) return (p - from).norm();
      double nearest = 1e300;
      for (const Eigen::Vector2d& v : visited_) nearest = std::min(nearest, (p - v).norm());
      return nearest;
    };
    Eigen::Vector2d best = RandomPoint(0.5);
    const int candidates = scenario_ == Scenario::kCorridor ? 8 : 4;
    for (int tries = 0, found = 0; tries < 40 && found < candidates; ++tries) {
      const Eigen::Vector2d p = RandomPoint(0.5);
      if ((p - from).norm() < min_goal_distance_m_) continue;
      if (found == 0 || score(p) > score(best)) best = p;
      ++found;
    }
    visited_.push_back(best);
    return best;
  }

 private:
  const FreeSpace& fs_;
  const Scenario scenario_;
  const double min_goal_distance_m_;
  SplitMix64& rng_;
  std::vector<Eigen::Vector2d> visited_;
};

// Stopped: scanning the room, the head swinging `amplitude` to either side once.
struct Stop {
  double total = 0, elapsed = 0, amplitude = 0;
  double Scan() const { return amplitude * std::sin(2 * M_PI * elapsed / total); }
};

// The stop at the end of a leg: a random length, and a scan no faster than about
// 1.6 rad/s at its peak (faster is not looking any more).
Stop NextStop(const SimulatorOptions& o, SplitMix64& rng) {
  Stop stop;
  stop.total = rng.Uniform(o.min_stop_s, o.max_stop_s);
  stop.amplitude = std::min(o.max_scan_rad * rng.Uniform(0.5, 1.0), 0.25 * stop.total) *
                   (rng.Next() % 2 ? 1 : -1);
  return stop;
}

// The body turned (at a human rate, over dt) towards the point ahead of it.
double TurnTowards(double body, const Eigen::Vector2d& ahead, const SimulatorOptions& o) {
  if (ahead.norm() <= 1e-6) return body;
  const double turn = WrapAngle(std::atan2(ahead.y(), ahead.x()) - body);
  const double max_turn = o.max_turn_rate_rad_s * o.pose_period_s;
  return WrapAngle(body + std::clamp(turn, -max_turn, max_turn));
}

std::vector<HeadSample> GenerateWalk(const FreeSpace& fs, Scenario scenario,
                                     const SimulatorOptions& o, SplitMix64& rng) {
  GoalChooser goals(fs, scenario, o.min_goal_distance_m, rng);
  const double dt = o.pose_period_s;
  const HeadSwing swing(rng);
  Eigen::Vector2d position = goals.Start();
  double body = rng.Uniform(-M_PI, M_PI);
  bool stopped = true;
  Stop stop;
  stop.total = o.first_stop_s;
  stop.amplitude = std::min(o.max_scan_rad, 0.25 * stop.total) * (rng.Next() % 2 ? 1 : -1);
  Leg leg;
  double along = 0.0, walked = 0.0;
  std::vector<HeadSample> out;
  for (double t = 0.0; t <= o.max_duration_s; t += dt) {
    // The head: looking around while walking, the scan when stopped, pitch swinging.
    const double scan = stopped ? stop.Scan() : 0.0;
    out.push_back({position, WrapAngle(body + swing.Look(t, o) + scan), swing.Pitch(t, o)});
    if (walked >= o.target_length_m) break;
    if (stopped) {
      stop.elapsed += dt;
      if (stop.elapsed < stop.total) continue;
      std::vector<Eigen::Vector2d> path;
      for (int tries = 0; tries < 20 && path.size() < 2; ++tries)
        path = fs.Path(position, goals.Next(position));
      if (path.size() < 2) break;  // nowhere to go: the walk ends here
      leg = MakeLeg(std::move(path), rng.Uniform(o.min_speed_mps, o.max_speed_mps));
      along = 0.0;
      stopped = false;
    }
    along = std::min(along + leg.speed * dt, leg.Length());
    const Eigen::Vector2d next = leg.At(along);
    walked += (next - position).norm();
    position = next;
    // The body turns towards the path a metre ahead.
    body = TurnTowards(body, leg.At(along + 1.0) - position, o);
    if (along >= leg.Length()) {
      stopped = true;
      stop = NextStop(o, rng);
    }
  }
  return out;
}

// The given trajectory at the pose period (linear in position and angles).
std::vector<HeadSample> Resample(const std::vector<TimedPose>& trajectory, double dt) {
  std::vector<HeadSample> out;
  if (trajectory.empty()) return out;
  const double t0 = trajectory.front().t_s, t1 = trajectory.back().t_s;
  size_t i = 0;
  for (int k = 0; t0 + k * dt <= t1 + 1e-9; ++k) {
    const double t = t0 + k * dt;
    while (i + 1 < trajectory.size() && trajectory[i + 1].t_s < t) ++i;
    const TimedPose& a = trajectory[i];
    const TimedPose& b = trajectory[std::min(i + 1, trajectory.size() - 1)];
    const double span = b.t_s - a.t_s;
    const double f = span > 0 ? std::clamp((t - a.t_s) / span, 0.0, 1.0) : 0.0;
    out.push_back({a.position + f * (b.position - a.position),
                   WrapAngle(a.heading + f * WrapAngle(b.heading - a.heading)),
                   a.pitch + f * (b.pitch - a.pitch)});
  }
  return out;
}

Se2 ToSe2(const Pose2& p) { return {p.heading, p.position}; }

}  // namespace

std::vector<TimedPose> WalkWaypoints(const std::vector<TimedPose>& waypoints,
                                     const SimulatorOptions& o) {
  std::vector<TimedPose> out;
  if (waypoints.size() < 2 || !(o.pose_period_s > 0)) return out;
  SplitMix64 rng = Stream(o.seed, 8);
  const HeadSwing swing(rng);
  const double dt = o.pose_period_s, scan_s = o.first_stop_s;
  const double amplitude = std::min(o.max_scan_rad, 0.25 * scan_s) * (rng.Next() % 2 ? 1 : -1);
  const Eigen::Vector2d first_leg = waypoints[1].position - waypoints[0].position;
  double body = std::atan2(first_leg.y(), first_leg.x());
  const double t0 = waypoints.front().t_s - scan_s;
  size_t i = 0;
  for (double t = t0; t <= waypoints.back().t_s + 1e-9; t += dt) {
    while (i + 2 < waypoints.size() && waypoints[i + 1].t_s <= t) ++i;
    const TimedPose& a = waypoints[i];
    const TimedPose& b = waypoints[i + 1];
    const double span = b.t_s - a.t_s;
    const double f = span > 0 ? std::clamp((t - a.t_s) / span, 0.0, 1.0) : 1.0;
    TimedPose pose;
    pose.t_s = t - t0;
    pose.position = a.position + f * (b.position - a.position);
    // The body turns at a human rate towards the leg it walks; at the start it scans.
    const Eigen::Vector2d leg = b.position - a.position;
    if (t >= waypoints.front().t_s && leg.norm() > 1e-6) {
      const double turn = WrapAngle(std::atan2(leg.y(), leg.x()) - body);
      body = WrapAngle(body +
                       std::clamp(turn, -o.max_turn_rate_rad_s * dt, o.max_turn_rate_rad_s * dt));
    }
    const double scan =
        t < waypoints.front().t_s ? amplitude * std::sin(2 * M_PI * (t - t0) / scan_s) : 0.0;
    pose.heading = WrapAngle(body + swing.Look(pose.t_s, o) + scan);
    pose.pitch = swing.Pitch(pose.t_s, o);
    out.push_back(pose);
  }
  return out;
}

std::optional<Scenario> ParseScenario(std::string_view name) {
  if (name == "corridor") return Scenario::kCorridor;
  if (name == "office") return Scenario::kOffice;
  if (name == "glass") return Scenario::kGlass;
  if (name == "hall") return Scenario::kHall;
  if (name == "mismatch") return Scenario::kMismatch;
  if (name == "doors") return Scenario::kDoors;
  if (name == "stale") return Scenario::kStale;
  if (name == "scaled") return Scenario::kScaled;
  if (name == "relocalize") return Scenario::kRelocalize;
  return std::nullopt;
}

const std::vector<std::string>& ScenarioNames() {
  static const std::vector<std::string> names = {
      "corridor", "office", "glass", "hall", "mismatch", "doors", "stale", "scaled", "relocalize"};
  return names;
}

const char* ToString(Scenario scenario) {
  switch (scenario) {
    case Scenario::kCorridor: return "corridor";
    case Scenario::kOffice: return "office";
    case Scenario::kGlass: return "glass";
    case Scenario::kHall: return "hall";
    case Scenario::kMismatch: return "mismatch";
    case Scenario::kDoors: return "doors";
    case Scenario::kStale: return "stale";
    case Scenario::kScaled: return "scaled";
    case Scenario::kRelocalize: return "relocalize";
  }
  return "?";
}

namespace {

// The plan as drawn, and what of it stands: in doors the plan has a line across every
// opening that reality lacks; in stale reality lost and moved walls since. Returns how
// the drawing differs from the building, in words.
std::string DrawPlan(const FloorPlan& input, const SimulatorOptions& o, SplitMix64& reality_rng,
                     Simulation* sim, Reality* initial) {
  sim->plan = input;
  const FloorPlan& plan = sim->plan;
  std::string drawn_text;
  if (o.scenario == Scenario::kDoors) {
    const std::vector<Segment> doors = DoorLines(input, o.max_door_m);
    sim->plan.segments.insert(sim->plan.segments.end(), doors.begin(), doors.end());
    drawn_text = Format(
        "doors: the plan draws the openings of 0.6-%.1f m closed (%.0f lines, one per "
        "face of a wall); reality has them open",
        o.max_door_m, static_cast<double>(doors.size()));
  }
  initial->plan_wall_present.assign(plan.segments.size(), 1);
  initial->plan_wall_glass.assign(plan.segments.size(), 0);
  initial->plan_wall_offset.assign(plan.segments.size(), Eigen::Vector2d::Zero());
  for (size_t i = input.segments.size(); i < plan.segments.size(); ++i)
    initial->plan_wall_present[i] = 0;
  if (o.scenario == Scenario::kStale) drawn_text = MarkStale(plan, o, reality_rng, initial);
  return drawn_text;
}

// Builds the scenario's reality and says, in words, how it differs from the plan. In hall
// a generated walk is kept to the plan's most open area.
std::string BuildScenario(RealityBuilder& builder, FreeSpace& free_space,
                          const std::string& drawn_text, const SimulatorOptions& o,
                          bool given_trajectory) {
  switch (o.scenario) {
    case Scenario::kCorridor:
      return "corridor: reality equals the plan; goals far apart (long hallways)";
    case Scenario::kDoors: return drawn_text;
    case Scenario::kStale: return drawn_text + builder.NewWalls(builder.reality.ceiling_m);
    case Scenario::kScaled: return "scaled: the plan was scanned from paper (below)";
    case Scenario::kRelocalize:
      return "relocalize: reality equals the plan; the headset loses tracking (below)";
    case Scenario::kOffice: return builder.Furnish();
    case Scenario::kGlass: return builder.Glass(o.glass_share);
    case Scenario::kMismatch: return builder.Mismatch(o.absent_share, builder.reality.ceiling_m);
    case Scenario::kHall: {
      // The most open area: cells far from every wall, around the most open one. A space
      // of 10 x 10 m has 5 m of clearance in its middle.
      const int centre = free_space.MostOpenCell();
      const double most = centre < 0 ? 0.0 : free_space.Clearance(free_space.CellCentre(centre));
      const double keep = std::min(3.0, 0.6 * most);
      const double ceiling = builder.reality.ceiling_m;
      if (given_trajectory)
        return Format("hall: ceiling %.1f m; the given trajectory decides where the walk goes",
                      ceiling);
      free_space.RestrictTo(centre, keep);
      return most >= 5.0
                 ? Format(
                       "hall: the walk stays in the plan's largest open area, at least %.1f m "
                       "from walls (%.0f m2); ceiling %.1f m",
                       keep, free_space.walkable_area_m2(), ceiling)
                 : Format(
                       "hall: the plan has no open area of 10 x 10 m; the walk stays in its "
                       "most open area instead, at least %.1f m from walls (%.0f m2); ceiling "
                       "%.1f m",
                       keep, free_space.walkable_area_m2(), ceiling);
    }
  }
  return "";
}

// The SLAM drift's draws for a walk.
struct Drift {
  double scale = 1.0;      // of distances walked
  double bias = 0.0;       // of heading, rad per metre
  double yaw_scale = 1.0;  // of angles turned
};

// Ground truth and the SLAM drift: the true motion between poses, integrated with a scale
// error, a heading bias and random walks, and the frame's jump at the end of each loss of
// tracking. The SLAM frame starts at the head, looking along +y (Unity's +z), as HoloLens
// sets it up.
Drift TrackSlam(const std::vector<HeadSample>& head, const std::vector<Loss>& losses,
                const SimulatorOptions& o, SplitMix64& drift_rng, Simulation* sim) {
  const double dt = o.pose_period_s;
  const double k = o.drift_scale;
  Drift drift;
  drift.scale = 1.0 + k * o.scale_error_sigma * drift_rng.Gaussian();
  drift.bias = k * o.heading_bias_rad_per_m * drift_rng.Uniform(0.5, 1.5) *
               (drift_rng.Next() % 2 ? 1.0 : -1.0);
  drift.yaw_scale = 1.0 + k * o.yaw_scale_error_sigma * drift_rng.Gaussian();
  const size_t n = head.size();
  Se2 slam{M_PI / 2, Eigen::Vector2d::Zero()};
  sim->steps.resize(n);
  for (size_t i = 0; i < n; ++i) {
    SimulatedStep& step = sim->steps[i];
    step.stamp_ns = static_cast<int64_t>(std::llround((o.start_s + i * dt) * 1e9));
    step.true_plan = {head[i].position, head[i].yaw, o.eye_height_m};
    if (i > 0) {
      const Se2 motion = ToSe2(sim->steps[i - 1].true_plan).Inverse() * ToSe2(step.true_plan);
      const double d = motion.t.norm();
      sim->length_m += d;
      const double heading_error =
          drift.bias * d + k * o.heading_walk_rad_per_sqrt_m * std::sqrt(d) * drift_rng.Gaussian() +
          k * o.heading_walk_rad_per_sqrt_s * std::sqrt(dt) * drift_rng.Gaussian() +
          (drift.yaw_scale - 1.0) * motion.theta;
      const Eigen::Vector2d position_error =
          k * o.position_walk_m_per_sqrt_m * std::sqrt(d) *
          Eigen::Vector2d(drift_rng.Gaussian(), drift_rng.Gaussian());
      slam = slam * Se2{motion.theta + heading_error, drift.scale * motion.t + position_error};
    }
    for (const Loss& loss : losses) {
      if (loss.to != i) continue;
      // Relocalized: the frame jumps about where the headset is.
      const Se2 jump = Se2{0.0, slam.t + loss.offset} * Se2{loss.angle, Eigen::Vector2d::Zero()} *
                       Se2{0.0, -slam.t};
      slam = jump * slam;
      sim->relocalizations.push_back(
          {o.start_s + loss.from * dt, o.start_s + loss.to * dt, jump, loss.offset.norm()});
    }
    step.T_slam_plan = slam * ToSe2(step.true_plan).Inverse();
    const double jitter_rad = k * o.jitter_rad * drift_rng.Gaussian();
    const Eigen::Vector2d jitter_m =
        k * o.jitter_m * Eigen::Vector2d(drift_rng.Gaussian(), drift_rng.Gaussian());
    step.slam = {slam.t + jitter_m, WrapAngle(slam.theta + jitter_rad), 0.0};
  }
  sim->T_slam_plan_initial = sim->steps[0].T_slam_plan;
  sim->duration_s = (n - 1) * dt;
  return drift;
}

// A plan wall the headset has meshed, at the pose it was first in the mesh within range.
struct MeshedWall {
  size_t step = 0;
  int segment = -1;
  Eigen::Vector2d point;
};

// The headset's spatial mapping: the patches its rays hit, gathered by chunk, and every
// mesh tick the meshes of the chunks that changed, re-meshed in the SLAM frame of the
// moment. It also finds the wall pick, a gaze hit on the mesh (thesis section 6.3.3).
class Mesher {
 public:
  Mesher(const SimulatorOptions& o, const std::vector<Surface>& surfaces,
         const std::vector<HeadSample>& head, double ceiling_m, SplitMix64& sensor_rng,
         SplitMix64& mesh_rng)
      : o_(o),
        surfaces_(surfaces),
        head_(head),
        ceiling_(ceiling_m),
        sensor_rng_(sensor_rng),
        mesh_rng_(mesh_rng) {}

  // What the rays of pose i hit, nearer than the maximum range.
  void See(size_t i);
  // The mesh tick at pose i: ADDED or UPDATED for the chunks seen anew (at most every
  // update_after_s), sometimes REMOVED for one far behind.
  void Emit(size_t i, SimulatedStep& step, MeshCounts& counts);
  // The pick: at the first pose from `earliest` on with a plan wall in the mesh within
  // sensor range, the wall patch nearest the wearer.
  void TryPick(size_t i, size_t earliest);
  const std::optional<MeshedWall>& picked() const { return picked_; }

 private:
  struct Chunk {
    std::set<PatchKey> seen;
    std::set<PatchKey> meshed;  // the patches in the mesh the headset has now
    bool live = false, dirty = false;
    double emitted_s = 0.0;
    uint64_t id = 0;
  };
  ChunkKey ChunkOf(const Eigen::Vector2d& p) const {
    return {static_cast<int>(std::floor(p.x() / o_.chunk_m)),
            static_cast<int>(std::floor(p.y() / o_.chunk_m))};
  }
  // Every patch seen so far, meshed with fresh noise in today's SLAM frame.
  void MeshPatches(const std::set<PatchKey>& patches, const Se2& T_slam_plan, SimMesh* mesh);

  const SimulatorOptions& o_;
  const std::vector<Surface>& surfaces_;
  const std::vector<HeadSample>& head_;
  double ceiling_;
  SplitMix64& sensor_rng_;
  SplitMix64& mesh_rng_;
  std::map<ChunkKey, Chunk> chunks_;
  std::vector<size_t> near_;  // the surfaces in reach of the pose being seen
  std::optional<MeshedWall> picked_;
};

void Mesher::See(size_t i) {
  const double eye = o_.eye_height_m;
  const Eigen::Vector3d eye_at(head_[i].position.x(), head_[i].position.y(), eye);
  near_.clear();
  for (size_t s = 0; s < surfaces_.size(); ++s)
    if ((surfaces_[s].centre - head_[i].position).norm() <= o_.max_range_m + surfaces_[s].radius)
      near_.push_back(s);
  for (int r = 0; r < o_.rays_h * o_.rays_v; ++r) {
    const double yaw = head_[i].yaw - 0.5 * o_.fov_h_rad +
                       (r % o_.rays_h + sensor_rng_.Uniform()) * o_.fov_h_rad / o_.rays_h;
    const double pitch = head_[i].pitch - 0.5 * o_.fov_v_rad +
                         (r / o_.rays_h + sensor_rng_.Uniform()) * o_.fov_v_rad / o_.rays_v;
    const Eigen::Vector3d d(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
                            std::sin(pitch));
    double best = o_.max_range_m;
    int hit = 0;  // a surface index, kFloor, kCeiling, or none (0 with best unchanged)
    bool any = false;
    if (d.z() < -1e-9 && -eye / d.z() < best) best = -eye / d.z(), hit = kFloor, any = true;
    if (d.z() > 1e-9 && (ceiling_ - eye) / d.z() < best)
      best = (ceiling_ - eye) / d.z(), hit = kCeiling, any = true;
    for (size_t s : near_) {
      const Surface& f = surfaces_[s];
      const double dn = d.dot(f.normal);
      if (std::abs(dn) < 1e-9) continue;
      const double t = (f.origin - eye_at).dot(f.normal) / dn;
      if (t <= 0 || t >= best) continue;
      const Eigen::Vector3d q = eye_at + t * d - f.origin;
      const double a = q.dot(f.u), b = q.dot(f.v);
      if (a < 0 || b < 0 || a > f.u_len || b > f.v_len) continue;
      best = t, hit = static_cast<int>(s), any = true;
    }
    // Nearer than the minimum range: seen, but the spatial mapping keeps none of it.
    if (!any || best < o_.min_range_m) continue;
    const Eigen::Vector3d p = eye_at + best * d;
    PatchKey key;
    Eigen::Vector2d centre;
    if (hit < 0) {
      const int ix = static_cast<int>(std::floor(p.x() / o_.floor_cell_m));
      const int iy = static_cast<int>(std::floor(p.y() / o_.floor_cell_m));
      key = {hit, ix, iy};
      centre = o_.floor_cell_m * Eigen::Vector2d(ix + 0.5, iy + 0.5);
    } else {
      const Surface& f = surfaces_[hit];
      const Eigen::Vector3d q = p - f.origin;
      const int iu = std::clamp(static_cast<int>(q.dot(f.u) / f.u_len * f.nu), 0, f.nu - 1);
      const int iv = std::clamp(static_cast<int>(q.dot(f.v) / f.v_len * f.nv), 0, f.nv - 1);
      key = {hit, iu, iv};
      centre = f.PatchCentre(iu, iv);
    }
    Chunk& chunk = chunks_[ChunkOf(centre)];
    if (chunk.seen.insert(key).second) chunk.dirty = true;
  }
}

void Mesher::Emit(size_t i, SimulatedStep& step, MeshCounts& counts) {
  const double dt = o_.pose_period_s;
  const double now_s = i * dt;
  for (auto& [key, chunk] : chunks_) {
    if (chunk.id == 0)  // from the chunk's place, like a spatial-mapping volume's id
      chunk.id = (static_cast<uint64_t>(key.first + (1 << 20)) << 21) +
                 static_cast<uint64_t>(key.second + (1 << 20)) + 1;
    const Eigen::Vector2d middle = o_.chunk_m * Eigen::Vector2d(key.first + 0.5, key.second + 0.5);
    if (!chunk.dirty) {
      // Far behind: the headset sometimes drops a surface; seen again, it comes back.
      if (chunk.live && (middle - head_[i].position).norm() >= o_.remove_min_distance_m &&
          mesh_rng_.Uniform() < o_.remove_rate_per_s * dt * o_.poses_per_mesh_tick) {
        step.meshes.push_back({chunk.id, MeshChange::kRemoved, {}, {}});
        ++counts.removed;
        chunk.live = false;
        chunk.seen.clear();
        chunk.meshed.clear();
      }
      continue;
    }
    if (chunk.live && now_s - chunk.emitted_s < o_.update_after_s) continue;
    SimMesh mesh;
    mesh.id = chunk.id;
    mesh.change = chunk.live ? MeshChange::kUpdated : MeshChange::kAdded;
    ++(chunk.live ? counts.updated : counts.added);
    chunk.live = true;
    chunk.dirty = false;
    chunk.emitted_s = now_s;
    chunk.meshed = chunk.seen;
    MeshPatches(chunk.seen, step.T_slam_plan, &mesh);
    counts.vertices += mesh.vertices_slam.size();
    counts.triangles += mesh.triangles.size() / 3;
    step.meshes.push_back(std::move(mesh));
  }
}

void Mesher::MeshPatches(const std::set<PatchKey>& patches, const Se2& T, SimMesh* mesh) {
  const double eye = o_.eye_height_m;
  auto vertex = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d noisy =
        p + o_.vertex_noise_m *
                Eigen::Vector3d(mesh_rng_.Gaussian(), mesh_rng_.Gaussian(), mesh_rng_.Gaussian());
    const Eigen::Vector2d xy = T * noisy.head<2>();
    mesh->vertices_slam.emplace_back(static_cast<float>(xy.x()), static_cast<float>(xy.y()),
                                     static_cast<float>(noisy.z() - eye));
  };
  auto quads = [&](uint32_t first, int su, int sv) {
    for (int b = 0; b < sv; ++b)
      for (int a = 0; a < su; ++a) {
        const uint32_t v00 = first + b * (su + 1) + a, v10 = v00 + 1;
        const uint32_t v01 = v00 + su + 1, v11 = v01 + 1;
        for (uint32_t t : {v00, v10, v11, v00, v11, v01}) mesh->triangles.push_back(t);
      }
  };
  for (const auto& [surface, iu, iv] : patches) {
    const auto first = static_cast<uint32_t>(mesh->vertices_slam.size());
    if (surface < 0) {
      const double z = surface == kFloor ? 0.0 : ceiling_;
      const double offset = o_.patch_noise_m * mesh_rng_.Gaussian();
      for (int b = 0; b <= 1; ++b)
        for (int a = 0; a <= 1; ++a)
          vertex({(iu + a) * o_.floor_cell_m, (iv + b) * o_.floor_cell_m, z + offset});
      quads(first, 1, 1);
      continue;
    }
    const Surface& f = surfaces_[surface];
    const int su = 1 + static_cast<int>(mesh_rng_.Next() % o_.max_subdivisions);
    const int sv = 1 + static_cast<int>(mesh_rng_.Next() % o_.max_subdivisions);
    const double pu = f.u_len / f.nu, pv = f.v_len / f.nv;
    const Eigen::Vector3d offset = o_.patch_noise_m * mesh_rng_.Gaussian() * f.normal;
    for (int b = 0; b <= sv; ++b)
      for (int a = 0; a <= su; ++a)
        vertex(f.origin + offset + (iu + static_cast<double>(a) / su) * pu * f.u +
               (iv + static_cast<double>(b) / sv) * pv * f.v);
    quads(first, su, sv);
  }
}

void Mesher::TryPick(size_t i, size_t earliest) {
  if (picked_ || i < earliest) return;
  double nearest = o_.max_range_m;
  for (const auto& [key, chunk] : chunks_)
    for (const auto& [surface, iu, iv] : chunk.meshed) {
      if (surface < 0 || surfaces_[surface].segment < 0) continue;
      const Eigen::Vector2d c = surfaces_[surface].PatchCentre(iu, iv);
      const double d = (c - head_[i].position).norm();
      if (d > nearest) continue;
      nearest = d;
      picked_ = MeshedWall{i, surfaces_[surface].segment, c};
    }
}

// The wall pick (thesis section 6.3.4): the plan side is the meshed wall picked (or,
// without a mesh or a meshed wall, the true nearest visible wall at `earliest`); the
// headset side is chosen so that AlignFromWallPick gives the truth composed with a random
// error of up to 9 degrees and 2.5 m about the wearer (thesis table 7.1), an error of the
// pick as a whole.
void PlacePick(const std::optional<MeshedWall>& picked, size_t earliest, const SimulatorOptions& o,
               SplitMix64& pick_rng, Simulation* sim) {
  const FloorPlan& plan = sim->plan;
  const Reality& reality = sim->reality;
  WallPick& pick = sim->pick;
  sim->pick_step = picked ? picked->step : earliest;
  const SimulatedStep& at = sim->steps[sim->pick_step];
  const Eigen::Vector2d wearer = at.true_plan.position;
  if (picked) {
    const Segment& s = plan.segments[picked->segment];
    pick.plan_point = ClosestPointOnSegment(s, picked->point);
    pick.plan_normal = s.Normal();
    if (pick.plan_normal.dot(wearer - pick.plan_point) < 0) pick.plan_normal *= -1.0;
  } else {
    double nearest = 1e300;
    for (size_t i = 0; i < plan.segments.size(); ++i) {
      if (!reality.plan_wall_present[i] || reality.plan_wall_glass[i]) continue;
      const Eigen::Vector2d c = ClosestPointOnSegment(plan.segments[i], wearer);
      if ((c - wearer).norm() >= nearest) continue;
      nearest = (c - wearer).norm();
      pick.plan_point = c;
      pick.plan_normal = plan.segments[i].Normal();
      if (pick.plan_normal.dot(wearer - c) < 0) pick.plan_normal *= -1.0;
    }
    if (nearest > 1e299) {  // every wall is glass or absent: pick the nearest plan wall
      for (const Segment& s : plan.segments) {
        const Eigen::Vector2d c = ClosestPointOnSegment(s, wearer);
        if ((c - wearer).norm() >= nearest) continue;
        nearest = (c - wearer).norm();
        pick.plan_point = c;
        pick.plan_normal = s.Normal();
      }
    }
  }
  double angle = pick_rng.Uniform(-o.max_pick_error_rad, o.max_pick_error_rad);
  double offset = pick_rng.Uniform(0.0, o.max_pick_offset_m);
  const double direction = pick_rng.Uniform(-M_PI, M_PI);
  if (o.kidnap_m > 0) {  // the same draws, so a kidnapped walk is the same walk
    angle = angle < 0 ? -o.kidnap_rad : o.kidnap_rad;
    offset = o.kidnap_m;
  }
  // About the wearer: E = Trans(wearer + offset) Rot(angle) Trans(-wearer).
  sim->pick_error =
      Se2{0.0, wearer + offset * Eigen::Vector2d(std::cos(direction), std::sin(direction))} *
      Se2{angle, Eigen::Vector2d::Zero()} * Se2{0.0, -wearer};
  const Se2 T_plan_slam = sim->pick_error * at.T_slam_plan.Inverse();
  pick.slam_point = T_plan_slam.Inverse() * pick.plan_point;
  pick.slam_normal = Se2{-T_plan_slam.theta, {0, 0}}.R() * pick.plan_normal;
  sim->pick_height_m = o.pick_height_m - o.eye_height_m;
}

// Ten markers at equal distances along the walk, the first at the start and the last at
// the end (thesis section 5.1), each on the nearest pose.
void PlaceMarkers(Simulation* sim) {
  const size_t kept = sim->steps.size();
  std::vector<double> along(kept, 0.0);
  for (size_t i = 1; i < kept; ++i)
    along[i] = along[i - 1] +
               (sim->steps[i].true_plan.position - sim->steps[i - 1].true_plan.position).norm();
  for (uint32_t m = 1; m <= 10; ++m) {
    const double target = along.back() * (m - 1) / 9.0;
    size_t i = std::lower_bound(along.begin(), along.end(), target) - along.begin();
    i = std::min(i, kept - 1);
    if (i > 0 && target - along[i - 1] < along[i] - target) --i;
    sim->steps[i].marker = m;
  }
}

// The settings of a simulation, human-readable, for SimulationInfo.
struct Settings {
  std::string scenario;  // how reality differs from the plan
  std::string region;    // where the walk may go
  bool given_trajectory = false;
  Drift drift;
  std::string scaled;  // how the plan was scaled and skewed
  bool picked_on_mesh = false;
};

std::string Describe(const Simulation& sim, const SimulatorOptions& o, const Settings& set) {
  const double k = o.drift_scale;
  const double angle_deg = sim.pick_error.theta / kDeg;
  std::string text = std::string("scenario ") + set.scenario + ". ";
  text += "Walkable region: " + set.region + ". ";
  text +=
      set.given_trajectory
          ? Format("Walk: the given trajectory, %.0f m in %.0f s. ", sim.length_m, sim.duration_s)
          : Format(
                "Walk: random goals joined by A* paths, %.1f-%.1f m/s, stops of "
                "%.0f-%.0f s; ",
                o.min_speed_mps, o.max_speed_mps, o.min_stop_s, o.max_stop_s) +
                Format("%.0f m in %.0f s (target %.0f m). ", sim.length_m, sim.duration_s,
                       o.target_length_m);
  text += Format("Headset: poses every %.2f s, eye height %.2f m; sensor %.1f-%.1f m, ",
                 o.pose_period_s, o.eye_height_m, o.min_range_m, o.max_range_m) +
          Format("field of view %.0f x %.0f deg. ", o.fov_h_rad / kDeg, o.fov_v_rad / kDeg);
  text += o.mesh ? Format(
                       "Mesh: %.0f m chunks, patches of %.2f m, noise %.3f m per patch and "
                       "%.3f m per vertex; ",
                       o.chunk_m, o.patch_m, o.patch_noise_m, o.vertex_noise_m) +
                       Format("updated at most every %.0f s; walls and ceiling %.1f m. ",
                              o.update_after_s, sim.reality.ceiling_m)
                 : std::string("Mesh: off. ");
  text += Format("SLAM drift: scale error %+.2f%%, heading bias %+.4f deg/m, ",
                 100.0 * (set.drift.scale - 1.0), set.drift.bias / kDeg) +
          Format("heading walk %.4f rad/sqrt(m), yaw scale error %+.2f%%. ",
                 k * o.heading_walk_rad_per_sqrt_m, 100.0 * (set.drift.yaw_scale - 1.0));
  text += set.scaled;
  for (const Relocalization& r : sim.relocalizations)
    text += Format("Tracking lost at %.1f s for %.1f s, then the frame jumped %.2f m", r.lost_s,
                   r.found_s - r.lost_s, r.jump_m) +
            Format(" and %.1f deg. ", r.jump.theta / kDeg);
  text += Format("Wall pick at %.1f s", (sim.steps[sim.pick_step].stamp_ns * 1e-9 - o.start_s));
  if (o.mesh && !set.picked_on_mesh) text += " (no plan wall ever meshed: an unseen one)";
  text += Format(", error: %.1f deg, %.2f m about the wearer.", angle_deg,
                 (sim.pick_error * sim.steps[sim.pick_step].true_plan.position -
                  sim.steps[sim.pick_step].true_plan.position)
                     .norm());
  return text;
}

// Why a plan or options cannot be simulated; empty when they can.
std::string InvalidInput(const FloorPlan& input, const SimulatorOptions& o) {
  if (input.segments.empty()) return "the plan has no walls";
  if (!(o.pose_period_s > 0) || o.rays_h < 1 || o.rays_v < 1 || o.poses_per_mesh_tick < 1 ||
      !(o.chunk_m > 0) || !(o.patch_m > 0) || !(o.floor_cell_m > 0) || o.max_subdivisions < 1)
    return "invalid simulator options";
  return {};
}

// The headset maps what it sees along the walk (nothing while tracking is lost) and the
// wearer picks a wall on the mesh; places the pick and says whether it was on the mesh.
bool MeshAndPick(const SimulatorOptions& o, const std::vector<Surface>& surfaces,
                 const std::vector<HeadSample>& head, const std::vector<uint8_t>& lost,
                 SplitMix64& sensor_rng, SplitMix64& mesh_rng, SplitMix64& pick_rng,
                 Simulation* sim) {
  const size_t n = head.size();
  const size_t earliest_pick =
      std::min(n - 1, static_cast<size_t>(std::llround(o.pick_time_s / o.pose_period_s)));
  Mesher mesher(o, surfaces, head, sim->reality.ceiling_m, sensor_rng, mesh_rng);
  for (size_t i = 0; i < n && o.mesh; ++i) {
    if (lost[i]) continue;
    mesher.See(i);
    if (i % o.poses_per_mesh_tick == 0) mesher.Emit(i, sim->steps[i], sim->counts);
    mesher.TryPick(i, earliest_pick);
  }
  PlacePick(mesher.picked(), earliest_pick, o, pick_rng, sim);
  return mesher.picked().has_value();
}

}  // namespace

Simulation Simulate(const FloorPlan& input, const SimulatorOptions& o,
                    const std::vector<TimedPose>* trajectory) {
  Simulation sim;
  sim.error = InvalidInput(input, o);
  if (!sim.error.empty()) return sim;
  // Every plan and scenario gets its own draws for a seed: the SLAM drift and the wall
  // pick's error would otherwise repeat across a suite's plans (three seeds, three
  // pick errors).
  const uint64_t walk_key = o.seed ^ Fnv1a(input.id) ^ (static_cast<uint64_t>(o.scenario) << 56);
  SplitMix64 reality_rng = Stream(walk_key, 1), walk_rng = Stream(walk_key, 2);
  SplitMix64 drift_rng = Stream(walk_key, 3), sensor_rng = Stream(walk_key, 4);
  SplitMix64 mesh_rng = Stream(walk_key, 5), pick_rng = Stream(walk_key, 6);
  SplitMix64 loss_rng = Stream(walk_key, 7);
  const double dt = o.pose_period_s;
  Settings settings;
  settings.given_trajectory = trajectory != nullptr;

  Reality initial;
  const std::string drawn_text = DrawPlan(input, o, reality_rng, &sim, &initial);
  const FloorPlan& plan = sim.plan;
  // Where one can walk: the plan's walls, all of them (so the walk never crosses one, even
  // where reality lacks it); in the scenarios of a plan that differs from the building,
  // the walls that stand.
  const bool reality_first = o.scenario == Scenario::kDoors || o.scenario == Scenario::kStale;
  FreeSpaceOptions fso;
  fso.body_radius_m = o.body_radius_m;
  FreeSpace free_space(reality_first ? StandingWalls(plan, initial) : plan.segments, plan.min,
                       plan.max, fso);
  std::vector<HeadSample> head;
  std::vector<Eigen::Vector2d> keep_clear;  // a given trajectory: no objects on it
  if (trajectory) {
    head = Resample(*trajectory, dt);
    if (head.size() < 2) {
      sim.error = "the trajectory needs at least two poses spanning one pose period";
      return sim;
    }
    for (const HeadSample& h : head) keep_clear.push_back(h.position);
  } else if (free_space.empty()) {
    sim.error = "no walkable region on the plan";
    return sim;
  }
  RealityBuilder builder(plan, free_space, keep_clear, reality_rng, std::move(initial));
  builder.reality.ceiling_m = o.scenario == Scenario::kHall ? o.hall_ceiling_m : o.ceiling_m;
  settings.scenario = BuildScenario(builder, free_space, drawn_text, o, trajectory != nullptr);
  settings.region = free_space.region();
  sim.reality = builder.reality;
  const std::vector<Surface> surfaces = RealSurfaces(plan, sim.reality, o.patch_m);

  if (!trajectory) head = GenerateWalk(free_space, o.scenario, o, walk_rng);
  if (head.size() < 2) {
    sim.error = "the walk is too short";
    return sim;
  }
  const size_t n = head.size();
  const std::vector<Loss> losses =
      o.scenario == Scenario::kRelocalize ? DrawLosses(n, o, loss_rng) : std::vector<Loss>{};
  std::vector<uint8_t> lost(n, 0);  // no poses and no meshes while lost
  for (const Loss& loss : losses)
    for (size_t i = loss.from; i < loss.to; ++i) lost[i] = 1;
  settings.drift = TrackSlam(head, losses, o, drift_rng, &sim);
  settings.picked_on_mesh =
      MeshAndPick(o, surfaces, head, lost, sensor_rng, mesh_rng, pick_rng, &sim);
  if (!losses.empty()) DropLostSteps(lost, &sim);  // while lost, the headset sends nothing
  if (o.scenario == Scenario::kScaled) settings.scaled = ScaleAndSkew(input, o, reality_rng, &sim);
  PlaceMarkers(&sim);
  sim.description = Describe(sim, o, settings);
  return sim;
}

Se2 FitSe2(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to) {
  const size_t n = std::min(from.size(), to.size());
  if (n < 2) return Se2::Identity();
  Eigen::Vector2d mf = Eigen::Vector2d::Zero(), mt = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < n; ++i) mf += from[i], mt += to[i];
  mf /= static_cast<double>(n);
  mt /= static_cast<double>(n);
  // In 2D the SVD of the cross-covariance reduces to one angle: the rotation maximising
  // sum (t_i - mt) . R (f_i - mf).
  double dot = 0.0, cross = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d a = from[i] - mf, b = to[i] - mt;
    dot += a.dot(b);
    cross += Cross(a, b);
  }
  Se2 T{std::atan2(cross, dot), Eigen::Vector2d::Zero()};
  T.t = mt - T.R() * mf;
  return T;
}

std::string ClimbStairs(Simulation* simulation, size_t at_step, double floor_height_m,
                        double climb_s) {
  std::vector<SimulatedStep>& steps = simulation->steps;
  if (at_step + 1 >= steps.size() || at_step <= simulation->pick_step)
    return "the stairs must come after the wall pick and before the last step";
  if (!(std::isfinite(floor_height_m) && floor_height_m > 0 && climb_s > 0))
    return "the floor height and the climb must be positive";
  const int64_t period_ns = steps[at_step + 1].stamp_ns - steps[at_step].stamp_ns;
  const int n = std::max(1, static_cast<int>(std::lround(climb_s * 1e9 / period_ns)));
  constexpr uint64_t kUpstairs = uint64_t{1} << 40;  // mesh ids of the upper floor
  std::set<uint64_t> seen_upstairs;
  for (size_t i = at_step + 1; i < steps.size(); ++i) {
    SimulatedStep& step = steps[i];
    step.stamp_ns += n * period_ns;
    step.slam.z += floor_height_m;
    step.floor = 1;
    std::vector<SimMesh> kept;
    for (SimMesh& mesh : step.meshes) {
      mesh.id += kUpstairs;
      const bool known = seen_upstairs.count(mesh.id) > 0;
      if (mesh.change == MeshChange::kRemoved) {
        if (!known) continue;
        seen_upstairs.erase(mesh.id);
      } else {
        if (!known) mesh.change = MeshChange::kAdded;
        seen_upstairs.insert(mesh.id);
      }
      for (Eigen::Vector3f& v : mesh.vertices_slam) v.z() += static_cast<float>(floor_height_m);
      kept.push_back(std::move(mesh));
    }
    step.meshes = std::move(kept);
  }
  std::vector<SimulatedStep> climb;
  for (int j = 1; j <= n; ++j) {
    SimulatedStep step = steps[at_step];
    step.stamp_ns += j * period_ns;
    step.slam.z += floor_height_m * j / n;
    step.meshes.clear();
    step.marker = 0;
    step.floor = j == n ? 1 : 0;
    climb.push_back(std::move(step));
  }
  steps.insert(steps.begin() + static_cast<std::ptrdiff_t>(at_step) + 1, climb.begin(),
               climb.end());
  simulation->duration_s += static_cast<double>(n * period_ns) * 1e-9;
  return {};
}

DriftStats MeasureDrift(const Simulation& sim) {
  DriftStats stats;
  if (sim.steps.empty()) return stats;
  stats.length_m = sim.length_m;
  std::vector<Eigen::Vector2d> slam, truth;
  for (const SimulatedStep& s : sim.steps) {
    slam.push_back(s.slam.position);
    truth.push_back(s.true_plan.position);
  }
  stats.end_error_m = (sim.T_slam_plan_initial.Inverse() * slam.back() - truth.back()).norm();
  stats.best_fit = FitSe2(slam, truth);
  double sum = 0.0;
  for (size_t i = 0; i < slam.size(); ++i) {
    const double e = (stats.best_fit * slam[i] - truth[i]).norm();
    sum += e;
    stats.best_fit_max_m = std::max(stats.best_fit_max_m, e);
  }
  stats.best_fit_mean_m = sum / static_cast<double>(slam.size());
  return stats;
}

}  // namespace floorpose::sim
