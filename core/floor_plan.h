// A floor plan: wall faces as 2D line segments in the plan frame, metres.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/se2.h"

namespace floorpose {

struct Segment {
  Eigen::Vector2d a, b;
  double Length() const { return (b - a).norm(); }
  // Unit normal (left of a->b); walls are two-sided, so the sign carries no meaning.
  Eigen::Vector2d Normal() const {
    const Eigen::Vector2d d = (b - a).normalized();
    return {-d.y(), d.x()};
  }
};

// Closest point on a segment to p.
Eigen::Vector2d ClosestPointOnSegment(const Segment& s, const Eigen::Vector2d& p);

// The squared distance from p to the axis-aligned box [lo, hi], 0 inside it: no point of
// anything within the box is nearer p.
inline double SquaredDistanceToBox(const Eigen::Vector2d& p, const Eigen::Vector2d& lo,
                                   const Eigen::Vector2d& hi) {
  return (lo - p).cwiseMax(p - hi).cwiseMax(0.0).squaredNorm();
}

// What a line of a plan is. Walls, windows, glass and the outlines of stairs and elevators
// are barriers: nobody walks through them, and the headset may mesh them (glass and
// windows seldom). Doors and exits are openings: where people walk through.
enum class LineKind : uint8_t { kWall, kWindow, kGlass, kStairs, kElevator, kDoor, kExit };
constexpr bool IsOpening(LineKind k) { return k == LineKind::kDoor || k == LineKind::kExit; }
// Whether a headset that walks past the line meshes it: walls and the walls around stairs
// and elevators, not glass or windows.
constexpr bool IsMeshed(LineKind k) {
  return k == LineKind::kWall || k == LineKind::kStairs || k == LineKind::kElevator;
}
// "wall", "window", "glass", "stairs", "elevator", "door", "exit".
const char* LineKindName(LineKind kind);
// The name as LineKindName writes it, or a synonym that plans use ("opening" for a door,
// "glazing" and "curtain_wall" for glass, "stair" and "staircase" for stairs, "lift" for
// an elevator, "entrance" and "emergency_exit" for an exit); false when unknown.
bool ParseLineKind(std::string_view name, LineKind* kind);

struct PlanLine {
  Segment segment;
  LineKind kind = LineKind::kWall;
};

// A room or unit the plan names, with its outline (plan frame, a closed ring).
struct PlanRoom {
  std::string name;
  std::vector<Eigen::Vector2d> outline;
};

struct FloorPlan {
  std::string id;
  // The barriers, and what each is (kinds[i] of segments[i]; missing entries are walls).
  std::vector<Segment> segments;
  std::vector<LineKind> kinds;
  std::vector<PlanLine> openings;  // doors and exits
  std::vector<PlanRoom> rooms;
  Eigen::Vector2d min = Eigen::Vector2d::Zero(), max = Eigen::Vector2d::Zero();

  LineKind KindOf(size_t segment) const {
    return segment < kinds.size() ? kinds[segment] : LineKind::kWall;
  }
};

// Where a plan lies on the Earth: plan (x, y) turned by rotation_rad (counter-clockwise,
// from the plan's +x to east) are metres east and north of origin (WGS84 longitude,
// latitude, degrees), on the azimuthal equidistant plane about it.
struct Georeference {
  Eigen::Vector2d origin_lon_lat = Eigen::Vector2d::Zero();
  double rotation_rad = 0.0;
};

// Result of parsing: either a plan or a message saying what is wrong and where.
struct FloorPlanParse {
  FloorPlan plan;
  std::string error;            // empty on success
  size_t dropped_segments = 0;  // zero-length or duplicate
  // How the file's coordinates became plan metres when not as written (a WGS84 plan's
  // projection and origin), for the load log line; empty for a plan in metres.
  std::string frame;
  // A WGS84 plan's projection, or a local plan's properties.georeference; none else.
  std::optional<Georeference> georeference;
  bool ok() const { return error.empty(); }
};

// Cleans a list of raw segments: drops non-finite, zero-length (< 1 mm) and duplicate
// segments, computes the bounds. Fails on an empty result.
FloorPlanParse MakeFloorPlan(std::string id, std::vector<Segment> raw);
// The same for lines of every kind: barriers to segments and kinds, openings to openings
// (a duplicate is the same line of the same sort), rooms kept as they are. A door, exit,
// window or glass line drawn along a wall cuts that part out of the wall. Fails without
// a barrier.
FloorPlanParse MakeFloorPlan(std::string id, const std::vector<PlanLine>& lines,
                             std::vector<PlanRoom> rooms);

// The segments of a plan inside a box, cut at its border (Liang-Barsky), for the thesis'
// "floor plan clipped to the points' box + 2 m" (section 6.4.3). May be empty.
FloorPlan ClipFloorPlan(const FloorPlan& plan, const Eigen::Vector2d& min,
                        const Eigen::Vector2d& max);

// A fingerprint of the segments (FNV-1a over their coordinates): the same plan gives the
// same digest whatever file it came from; any moved wall changes it.
uint64_t FloorPlanDigest(const FloorPlan& plan);

// The thesis' text format: the segment count, then `x1 y1 x2 y2` per line (section 6.4.2).
FloorPlanParse ParseTextFloorPlan(std::string_view text, std::string id);

// Whether the step p -> q (plan frame) properly crosses a wall of the plan (touching
// does not count): a wearer does not walk through walls. With end_margin_m, only
// crossings at least that far from both ends of the wall count (a path a few
// centimetres off clips a door's jamb). Allocates nothing: for every pose.
bool StepCrossesPlan(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const FloorPlan& plan,
                     double end_margin_m = 0);

// A path's finite positions (slam frame, in order) moved onto the plan by T_plan_slam.
std::vector<Eigen::Vector2d> PathOnPlan(const Se2& T_plan_slam,
                                        const std::vector<Eigen::Vector2d>& path_slam);

// How many steps of a path (plan frame, in order) cross a wall, as StepCrossesPlan.
uint32_t PathCrossings(const std::vector<Eigen::Vector2d>& path, const FloorPlan& plan,
                       double end_margin_m = 0);

// How many of the wall points (plan frame) the wearer could not have seen from where they
// were: points with a position of the path within reach_m of them, but a plan wall
// (end_margin_m clear of its ends, as StepCrossesPlan) across the line of sight from
// every such position. The sight line stops standoff_m short of the point, so that the
// wall it lies on does not block it. Points out of reach of the path tell nothing and do
// not count.
uint32_t HiddenPoints(const std::vector<Eigen::Vector2d>& points,
                      const std::vector<Eigen::Vector2d>& path, const FloorPlan& plan,
                      double reach_m, double standoff_m, double end_margin_m = 0);

// The plan's walls in clear sight of a path (plan frame): samples every step_m along the
// walls min_length_m or longer, kept where a position of the path within reach_m has a
// clear line of sight to them (as HiddenPoints). What a headset walking that path scans.
struct WallSampleOptions {
  double reach_m = 2.0;
  double step_m = 0.25;
  double standoff_m = 0.3;
  double end_margin_m = 0;
  double min_length_m = 0;
};
std::vector<Eigen::Vector2d> WallSamplesInSight(const std::vector<Eigen::Vector2d>& path,
                                                const FloorPlan& plan,
                                                const WallSampleOptions& options);

// The plan's walls the wearer should have seen from the path (plan frame) and did not:
// WallSamplesInSight, and of those, how many have no wall point (plan frame) within about
// match_m. Under the true place a headset misses few walls it walked past (glass, clutter
// and a plan that lacks changes aside); under a look-alike the walls seen lie on some of
// its walls, but the plan has others there that nobody saw.
struct UnseenWallsOptions {
  // Walls surely scanned when passed within 2 m. Shorter walls than 1.5 m (a column, a
  // jamb, a thin partition drawn as a box) do not count: the headset meshes them poorly
  // and plans draw them loosely.
  WallSampleOptions walls{2.0, 0.25, 0.3, 0, 1.5};
  double match_m = 0.3;
};
struct UnseenWalls {
  uint32_t expected = 0, missed = 0;
};
UnseenWalls CountUnseenWalls(const std::vector<Eigen::Vector2d>& points,
                             const std::vector<Eigen::Vector2d>& path, const FloorPlan& plan,
                             const UnseenWallsOptions& options = {});

}  // namespace floorpose
