// A floor's plan and what is made from it (the closest-wall index, the plan search's grids,
// routes, rooms and the explored map), read and built on any thread; and the plans in use:
// one plan file, or one floor of a .floors set with every other floor built beside it, so
// that a floor change on the stairs costs the poses nothing.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "core/closest_wall_index.h"
#include "core/explored_map.h"
#include "core/global_search.h"
#include "core/route_planner.h"
#include "floorpose/v1/config.pb.h"
#include "platform/floor_follower.h"
#include "platform/floor_plan_io.h"

namespace floorpose::platform {

// The plan's GlobalSearch grids, built on first use by the thread that runs the job.
class GlobalSearchCache {
 public:
  GlobalSearchCache(FloorPlan plan, GlobalSearchOptions options)
      : plan_(std::move(plan)), options_(options) {}
  const GlobalSearch& Get();

 private:
  FloorPlan plan_;
  GlobalSearchOptions options_;
  std::once_flag once_;
  std::unique_ptr<GlobalSearch> search_;
};

struct PlanAssets {
  std::shared_ptr<const ClosestWallIndex> index;
  std::shared_ptr<GlobalSearchCache> global;
  std::unique_ptr<RoutePlanner> routes;
  std::unique_ptr<ExploredMap> explored;
  std::string id;
  uint64_t digest = 0;           // FloorPlanDigest
  uint64_t explored_sent = 0;    // the explored map's revision last published
  int64_t next_explored_ns = 0;  // ...and when it is published next, if changed
};

// A plan read and built, with what a .floors set brings.
struct PlanLoad {
  std::string error;  // why it was refused; the rest is then empty
  std::string path, floor, file;
  FloorSet set;
  PlanAssets assets;
  std::map<std::string, PlanAssets> others;
};

// Reads and builds a plan file, or floor `floor` of a .floors set with every other floor;
// touches nothing but its arguments. Refused: a plan that does not load, or is out of
// limits (coordinates, extent); grids are made coarser to stay within
// limits.max_plan_memory_mb.
PlanLoad ReadPlan(const v1::FloorposedConfig& config, const std::function<int64_t()>& now_ns,
                  const std::string& path, const std::string& floor);
// A plan's index, search, routes, rooms and explored map.
PlanAssets BuildPlan(const v1::FloorposedConfig& config, const std::function<int64_t()>& now_ns,
                     const FloorPlanParse& parsed, const std::string& file);

// The plan in use, and for a .floors set the floors not in use and which floor the
// headset's height says.
class PlansInUse {
 public:
  explicit PlansInUse(std::string floor) : floor_(std::move(floor)) {}

  // A load that was not refused becomes the plan in use.
  void Take(PlanLoad load);
  // No plan.
  void Clear();
  // The floor the headset's height says, once it has said so for hold_s (FloorFollower).
  std::optional<FloorFollower::Change> Follow(double slam_z, int64_t stamp_ns, double margin_m,
                                              double hold_s) {
    return follower_.Observe(floor_, slam_z, stamp_ns, margin_m, hold_s);
  }
  // Floor `to` of the set in use becomes the plan in use, the floor left kept as it is;
  // false: not a floor of the set.
  bool ChangeFloor(const FloorEntry& to, double slam_z);

  PlanAssets& current() { return current_; }
  const PlanAssets& current() const { return current_; }
  const std::string& floor() const { return floor_; }
  const std::string& path() const { return path_; }  // as loaded: a plan or a .floors set

 private:
  std::string floor_;
  std::string path_;
  FloorFollower follower_;
  PlanAssets current_;
  std::map<std::string, PlanAssets> others_;
};

}  // namespace floorpose::platform
