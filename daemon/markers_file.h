// The team's markers kept in the state directory (state_dir/markers.pb): read at start,
// written again whenever the board has changed since.
#pragma once

#include <spdlog/spdlog.h>

#include <cstdint>
#include <string>

#include "platform/team.h"

namespace floorpose {

class MarkersFile {
 public:
  // Merges what `path` holds into the board (a missing file is none); from here on the
  // board is saved there.
  void Open(const std::string& path, platform::MarkerBoard& board) {
    path_ = path;
    std::string error;
    if (!board.Load(path_, &error)) spdlog::warn("markers {} not read: {}", path_, error);
    saved_ = board.revision();
    if (!board.markers().empty()) spdlog::info("{} markers from {}", board.markers().size(), path_);
  }
  // Writes the board when it changed since the last write (nothing before Open).
  void Save(const platform::MarkerBoard& board) {
    if (path_.empty() || board.revision() == saved_) return;
    std::string error;
    if (!board.Save(path_, &error)) spdlog::warn("markers not saved to {}: {}", path_, error);
    saved_ = board.revision();
  }

 private:
  std::string path_;    // empty: not kept
  uint64_t saved_ = 0;  // MarkerBoard::revision() last written
};

}  // namespace floorpose
