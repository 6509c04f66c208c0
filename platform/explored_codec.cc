#include "platform/explored_codec.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

namespace floorpose::platform {

v1::ExploredMap ToProto(const ExploredMap& map, const std::string& plan_id,
                        const std::string& floor, int64_t stamp_ns) {
  v1::ExploredMap out;
  const GridGeometry& g = map.grid();
  out.set_plan_id(plan_id);
  out.set_floor(floor);
  out.set_origin_x(g.origin.x());
  out.set_origin_y(g.origin.y());
  out.set_cell_m(g.cell_m);
  out.set_width(static_cast<uint32_t>(g.nx));
  out.set_height(static_cast<uint32_t>(g.ny));
  out.set_log_odds_scale(kExploredLogOddsScale);
  std::vector<int8_t> cells(g.size());
  uint32_t free = 0, walls = 0;
  for (size_t i = 0; i < cells.size(); ++i) {
    const double l = std::round(map.log_odds()[i] * kExploredLogOddsScale);
    cells[i] = static_cast<int8_t>(std::clamp(l, -127.0, 127.0));
    free += cells[i] < 0;
    walls += cells[i] > 0;
  }
  uLongf size = compressBound(static_cast<uLong>(cells.size()));
  std::string packed(size, '\0');
  compress2(reinterpret_cast<Bytef*>(packed.data()), &size,
            reinterpret_cast<const Bytef*>(cells.data()), static_cast<uLong>(cells.size()),
            Z_BEST_SPEED);
  packed.resize(size);
  out.set_log_odds_zlib(std::move(packed));
  out.set_free_cells(free);
  out.set_wall_cells(walls);
  out.set_stamp_ns(stamp_ns);
  if (const RoomMap* rooms = map.rooms()) {
    out.set_rooms(static_cast<uint32_t>(rooms->rooms().size()));
    for (int id : map.VisitedRooms()) {
      const Room& room = rooms->rooms()[id];
      v1::ExploredMap::Room* r = out.add_visited();
      r->set_id(static_cast<uint32_t>(id));
      r->set_x(room.centre.x());
      r->set_y(room.centre.y());
      r->set_area_m2(room.area_m2);
      r->set_poses(static_cast<uint32_t>(map.visits().at(id)));
    }
  }
  return out;
}

std::string UnpackExploredCells(const v1::ExploredMap& msg, std::vector<int8_t>* cells) {
  if (!(msg.log_odds_scale() > 0) || !std::isfinite(msg.log_odds_scale()))
    return "explored map without a log-odds scale";
  const uint64_t n = uint64_t{msg.width()} * msg.height();
  if (n == 0 || n > kMaxExploredCells)
    return "explored map of " + std::to_string(msg.width()) + " x " + std::to_string(msg.height()) +
           " cells (at most " + std::to_string(kMaxExploredCells) + ")";
  cells->assign(n, 0);
  uLongf size = static_cast<uLongf>(n);
  const int z = uncompress(reinterpret_cast<Bytef*>(cells->data()), &size,
                           reinterpret_cast<const Bytef*>(msg.log_odds_zlib().data()),
                           static_cast<uLong>(msg.log_odds_zlib().size()));
  if (z != Z_OK || size != n) {
    cells->clear();
    return "explored map cells do not unpack to " + std::to_string(n) + " bytes (zlib " +
           std::to_string(z) + ")";
  }
  return {};
}

std::string FromProto(const v1::ExploredMap& msg, ExploredMap* map) {
  const GridGeometry& g = map->grid();
  if (msg.width() != static_cast<uint32_t>(g.nx) || msg.height() != static_cast<uint32_t>(g.ny) ||
      std::abs(msg.cell_m() - g.cell_m) > 1e-9 || std::abs(msg.origin_x() - g.origin.x()) > 1e-6 ||
      std::abs(msg.origin_y() - g.origin.y()) > 1e-6)
    return "explored map of another grid (" + std::to_string(msg.width()) + " x " +
           std::to_string(msg.height()) + " cells of " + std::to_string(msg.cell_m()) +
           " m; expected " + std::to_string(g.nx) + " x " + std::to_string(g.ny) + " of " +
           std::to_string(g.cell_m) + " m)";
  std::vector<int8_t> cells;
  if (std::string error = UnpackExploredCells(msg, &cells); !error.empty()) return error;
  std::map<int, int> visits;
  const int rooms = map->rooms() ? static_cast<int>(map->rooms()->rooms().size()) : 0;
  for (const auto& r : msg.visited()) {
    if (static_cast<int>(r.id()) >= rooms)
      return "explored map names room " + std::to_string(r.id()) + " of a plan with " +
             std::to_string(rooms) + " rooms";
    visits[static_cast<int>(r.id())] = static_cast<int>(r.poses());
  }
  std::vector<float> log_odds(cells.size());
  for (size_t i = 0; i < cells.size(); ++i)
    log_odds[i] = static_cast<float>(cells[i] / msg.log_odds_scale());
  map->SetLogOdds(std::move(log_odds));
  map->SetVisits(std::move(visits));
  return {};
}

}  // namespace floorpose::platform
