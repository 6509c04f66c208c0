#include "core/rooms.h"

#include <algorithm>
#include <cmath>

namespace floorpose {
namespace {

// Virtual segments across the door gaps of `walls` (see rooms.h).
std::vector<Segment> CloseDoors(const std::vector<Segment>& walls, const RoomOptions& o) {
  struct End {
    Eigen::Vector2d p, out;  // the endpoint, and the wall's unit direction continued past it
    size_t wall;
  };
  std::vector<End> ends;
  for (size_t i = 0; i < walls.size(); ++i) {
    const Segment& s = walls[i];
    if (s.Length() < 1e-6) continue;
    const Eigen::Vector2d d = (s.b - s.a).normalized();
    ends.push_back({s.a, -d, i});
    ends.push_back({s.b, d, i});
  }
  std::sort(ends.begin(), ends.end(), [](const End& a, const End& b) {
    return a.p.x() != b.p.x() ? a.p.x() < b.p.x() : a.p.y() < b.p.y();
  });
  const double cos_max = std::cos(o.door_angle_rad);
  std::vector<Segment> doors;
  for (size_t i = 0; i < ends.size(); ++i)
    for (size_t j = i + 1; j < ends.size() && ends[j].p.x() - ends[i].p.x() <= o.max_door_m; ++j) {
      const End& a = ends[i];
      const End& b = ends[j];
      if (a.wall == b.wall) continue;
      const Eigen::Vector2d gap = b.p - a.p;
      const double width = gap.norm();
      if (width < 1e-3 || width > o.max_door_m) continue;
      const Eigen::Vector2d u = gap / width;
      // Each wall, continued past its end, runs into the gap: a's along u, b's against it.
      if (a.out.dot(u) < cos_max || -b.out.dot(u) < cos_max) continue;
      const Eigen::Vector2d n(-u.y(), u.x());
      const Segment& wa = walls[a.wall];
      const Segment& wb = walls[b.wall];
      if (std::abs((wa.a - b.p).dot(n)) > o.max_door_offset_m ||
          std::abs((wb.a - a.p).dot(n)) > o.max_door_offset_m)
        continue;
      doors.push_back({a.p, b.p});
    }
  return doors;
}

}  // namespace

RoomMap::RoomMap(const FloorPlan& plan, const RoomOptions& options) {
  // A margin of a few cells, so that the outside connects around the building.
  grid_ = GridGeometry::Cover(plan.min, plan.max, options.cell_m, 3 * options.cell_m,
                              options.max_cells);
  doors_ = CloseDoors(plan.segments, options);
  std::vector<Segment> closed = plan.segments;
  closed.insert(closed.end(), doors_.begin(), doors_.end());
  // Free: no wall or door passes through the cell.
  std::vector<uint8_t> free = CellsNearWalls(grid_, closed, grid_.cell_m * M_SQRT1_2);
  for (uint8_t& f : free) f = !f;
  const std::vector<uint8_t> tight = CellsNearWalls(grid_, closed, options.min_clearance_m);
  std::vector<int> pieces;
  const int count = LabelComponents(grid_, free, &pieces);
  std::vector<uint8_t> is_room(count, 0), outside(count, 0);
  for (int i = 0; i < static_cast<int>(grid_.size()); ++i) {
    if (pieces[i] < 0) continue;
    const int x = i % grid_.nx, y = i / grid_.nx;
    if (x == 0 || y == 0 || x == grid_.nx - 1 || y == grid_.ny - 1) outside[pieces[i]] = 1;
    if (!tight[i]) is_room[pieces[i]] = 1;
  }
  std::vector<int> id_of(count, -1);
  for (int k = 0; k < count; ++k)
    if (is_room[k] && !outside[k]) {
      id_of[k] = static_cast<int>(rooms_.size());
      rooms_.push_back({id_of[k], Eigen::Vector2d::Zero(), 0.0});
    }
  labels_.assign(grid_.size(), -1);
  std::vector<size_t> cells(rooms_.size(), 0);
  for (int i = 0; i < static_cast<int>(grid_.size()); ++i) {
    if (pieces[i] < 0 || id_of[pieces[i]] < 0) continue;
    const int id = labels_[i] = id_of[pieces[i]];
    rooms_[id].centre += grid_.CellCentre(i);
    ++cells[id];
  }
  for (Room& room : rooms_) {
    room.area_m2 = static_cast<double>(cells[room.id]) * grid_.cell_m * grid_.cell_m;
    room.centre /= static_cast<double>(cells[room.id]);
  }
  // The centroid of an L-shaped room can lie outside it: take its nearest cell instead.
  std::vector<double> best(rooms_.size(), 1e300);
  std::vector<Eigen::Vector2d> inside(rooms_.size());
  for (int i = 0; i < static_cast<int>(grid_.size()); ++i) {
    if (labels_[i] < 0) continue;
    const double d = (grid_.CellCentre(i) - rooms_[labels_[i]].centre).squaredNorm();
    if (d < best[labels_[i]]) best[labels_[i]] = d, inside[labels_[i]] = grid_.CellCentre(i);
  }
  for (Room& room : rooms_) room.centre = inside[room.id];
}

int RoomMap::RoomAt(const Eigen::Vector2d& p) const {
  const int cell = grid_.CellOf(p);
  return cell < 0 ? -1 : labels_[cell];
}

}  // namespace floorpose
