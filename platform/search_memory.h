// What the engine keeps for its searches of the whole plan: the wearer's recent path (a
// search weighs the walk that led to its places, and prices walks through walls), and
// the walls the last search ran on (a search on the same walls finds the same places,
// and would count twice towards their lead).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <optional>
#include <utility>
#include <vector>

namespace floorpose::platform {

class SearchMemory {
 public:
  // A pose's slam position at stamp_ns: kept when 0.25 m or more from the last kept, for
  // window_s seconds (0: for the last 5 km).
  void AddPosition(int64_t stamp_ns, const Eigen::Vector2d& position, double window_s);
  // The kept positions stamped since_ns or later, in order.
  std::vector<Eigen::Vector2d> PathSince(int64_t since_ns) const;
  // ...and stamped before until_ns.
  std::vector<Eigen::Vector2d> PathBetween(int64_t since_ns, int64_t until_ns) const;
  // Whether a search on these walls, checking the alignment of this version, would be a
  // new one; if so it is remembered as the last.
  bool NewSearch(const std::vector<Eigen::Vector2d>& cloud, uint64_t alignment_version);

 private:
  std::deque<std::pair<int64_t, Eigen::Vector2d>> path_;
  struct Walls {  // a cloud's count and sum, and the alignment's version
    size_t points = 0;
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    uint64_t version = 0;
    bool operator==(const Walls& o) const {
      return points == o.points && sum == o.sum && version == o.version;
    }
  };
  std::optional<Walls> last_;
};

}  // namespace floorpose::platform
