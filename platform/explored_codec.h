// The explored map on the wire (v1::ExploredMap): int8 log-odds, zlib-compressed.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/explored_map.h"
#include "floorpose/v1/floorpose.pb.h"

namespace floorpose::platform {

// Log-odds are sent times this, rounded, as signed bytes (|log-odds| <= 127 / 32 = 3.97).
inline constexpr double kExploredLogOddsScale = 32.0;

v1::ExploredMap ToProto(const ExploredMap& map, const std::string& plan_id,
                        const std::string& floor, int64_t stamp_ns);

// Reads a message into `map` (made from the same plan with the same cell size): its cells
// and room visits replace the map's. The error says what does not fit (another grid,
// a corrupt or truncated payload); then the map is unchanged.
std::string FromProto(const v1::ExploredMap& msg, ExploredMap* map);

// The message's cells as sent: width * height signed bytes (log-odds times
// log_odds_scale), row by row from origin_y upwards. The error says what is wrong (no
// scale, a grid over kMaxExploredCells, a corrupt or truncated payload).
inline constexpr uint64_t kMaxExploredCells = uint64_t{1} << 26;
std::string UnpackExploredCells(const v1::ExploredMap& msg, std::vector<int8_t>* cells);

}  // namespace floorpose::platform
