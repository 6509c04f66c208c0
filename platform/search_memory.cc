#include "platform/search_memory.h"

namespace floorpose::platform {

void SearchMemory::AddPosition(int64_t stamp_ns, const Eigen::Vector2d& position, double window_s) {
  if (!position.allFinite()) return;
  if (path_.empty() || (position - path_.back().second).norm() >= 0.25)
    path_.emplace_back(stamp_ns, position);
  while (window_s > 0 && !path_.empty() &&
         path_.front().first < stamp_ns - static_cast<int64_t>(window_s * 1e9))
    path_.pop_front();
  while (path_.size() > 20000) path_.pop_front();  // 5 km, when the window is everything
}

std::vector<Eigen::Vector2d> SearchMemory::PathSince(int64_t since_ns) const {
  return PathBetween(since_ns, INT64_MAX);
}

std::vector<Eigen::Vector2d> SearchMemory::PathBetween(int64_t since_ns, int64_t until_ns) const {
  std::vector<Eigen::Vector2d> path;
  for (const auto& [stamp, position] : path_)
    if (stamp >= since_ns && stamp < until_ns) path.push_back(position);
  return path;
}

bool SearchMemory::NewSearch(const std::vector<Eigen::Vector2d>& cloud,
                             uint64_t alignment_version) {
  Walls walls{cloud.size(), Eigen::Vector2d::Zero(), alignment_version};
  for (const Eigen::Vector2d& p : cloud) walls.sum += p;
  if (last_ == walls) return false;
  last_ = walls;
  return true;
}

}  // namespace floorpose::platform
