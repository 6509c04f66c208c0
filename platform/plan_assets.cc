#include "platform/plan_assets.h"

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "core/rooms.h"

namespace floorpose::platform {

const GlobalSearch& GlobalSearchCache::Get() {
  std::call_once(once_, [this] { search_ = std::make_unique<GlobalSearch>(plan_, options_); });
  return *search_;
}

namespace {

// Why a plan is refused before anything is built from it, or empty.
std::string PlanOutOfLimits(const FloorPlan& plan, const v1::LimitsConfig& limits) {
  const double max_coordinate = limits.max_plan_coordinate_m();
  for (const Eigen::Vector2d& corner : {plan.min, plan.max})
    if (!corner.allFinite() || corner.cwiseAbs().maxCoeff() > max_coordinate)
      return fmt::format("a coordinate beyond limits.max_plan_coordinate_m ({} m)", max_coordinate);
  const Eigen::Vector2d extent = plan.max - plan.min;
  if (extent.maxCoeff() > limits.max_plan_extent_m())
    return fmt::format("{:.0f} x {:.0f} m, larger than limits.max_plan_extent_m ({} m) on a side",
                       extent.x(), extent.y(), limits.max_plan_extent_m());
  return {};
}

// How many times coarser than configured a plan's grids must be to stay within
// limits.max_plan_memory_mb. Bytes a cell, as measured on ILC F1 (240 x 176 m: 436 MB of
// RSS at the default cells): routes 20 (passable, components, a search's distances and
// parents), rooms and explored maps 8 each, the closest-wall index 10 (its 8-byte cells
// and the lists of those with three candidates or more: 10.1 on MLSTRUCT 848).
double PlanGridScale(const FloorPlan& plan, const v1::FloorposedConfig& c) {
  const Eigen::Vector2d extent = (plan.max - plan.min).array() + 2.0;  // the grids' margins
  auto per_m2 = [](double bytes_per_cell, double cell_m) {
    return bytes_per_cell / (cell_m * cell_m);
  };
  const double bytes =
      extent.x() * extent.y() *
      (per_m2(20, c.routes().cell_m()) + per_m2(8, RoomOptions{}.cell_m) +
       per_m2(8, c.explored().cell_m()) + per_m2(10, ClosestWallIndex::Options{}.cell_m) +
       per_m2(2, ClosestWallIndex::Options{}.grid_cell_m));
  const double budget = static_cast<double>(c.limits().max_plan_memory_mb()) * (1 << 20);
  return std::max(1.0, std::sqrt(bytes / budget));
}

}  // namespace

PlanLoad ReadPlan(const v1::FloorposedConfig& config, const std::function<int64_t()>& now_ns,
                  const std::string& path, const std::string& floor) {
  auto Refused = [](std::string error) {
    PlanLoad refused;
    refused.error = std::move(error);
    return refused;
  };
  PlanLoad load;
  load.path = path;
  load.floor = floor;
  load.file = path;
  if (IsFloorSet(path)) {
    load.set = LoadFloorSet(path);
    const FloorEntry* entry = load.set.ok() ? load.set.Find(floor) : nullptr;
    if (load.set.ok() && !entry) load.set.error = path + ": no floor '" + floor + "' in the set";
    if (!load.set.ok()) return Refused(load.set.error);
    load.file = entry->plan_path;
  }
  const FloorPlanParse parsed = LoadFloorPlan(load.file);
  if (!parsed.ok()) return Refused(parsed.error);
  if (const std::string e = PlanOutOfLimits(parsed.plan, config.limits()); !e.empty())
    return Refused(load.file + ": " + e);
  // Every other floor of a set is built now, so that a floor change on the stairs costs
  // the poses nothing; one that does not load refuses the set.
  for (const FloorEntry& f : load.set.floors) {
    if (f.id == floor) continue;
    const FloorPlanParse other = LoadFloorPlan(f.plan_path);
    if (!other.ok()) return Refused(path + ": floor " + f.id + ": " + other.error);
    if (const std::string e = PlanOutOfLimits(other.plan, config.limits()); !e.empty())
      return Refused(path + ": floor " + f.id + ": " + e);
    load.others[f.id] = BuildPlan(config, now_ns, other, f.plan_path);
  }
  load.assets = BuildPlan(config, now_ns, parsed, load.file);
  return load;
}

PlanAssets BuildPlan(const v1::FloorposedConfig& config, const std::function<int64_t()>& now_ns,
                     const FloorPlanParse& parsed, const std::string& file) {
  PlanAssets a;
  const double scale = PlanGridScale(parsed.plan, config);
  if (scale > 1)
    spdlog::warn(
        "floor plan {}: grids {:.1f} times coarser than configured, to stay within "
        "limits.max_plan_memory_mb ({} MB)",
        file, scale, config.limits().max_plan_memory_mb());
  ClosestWallIndex::Options index_options;
  index_options.cell_m *= scale;
  index_options.grid_cell_m *= scale;
  index_options.max_distance_m = std::max(3.0, config.icp().max_correspondence_m());
  const int64_t t_index = now_ns();
  a.index = std::make_shared<const ClosestWallIndex>(parsed.plan, index_options);
  spdlog::info(
      "floor plan {}: {} segments ({} dropped), {:.1f} x {:.1f} m, index {:.1f} MB in {:.0f} ms",
      file, parsed.plan.segments.size(), parsed.dropped_segments,
      parsed.plan.max.x() - parsed.plan.min.x(), parsed.plan.max.y() - parsed.plan.min.y(),
      static_cast<double>(a.index->MemoryBytes()) / 1e6,
      static_cast<double>(now_ns() - t_index) * 1e-6);
  if (!parsed.frame.empty()) spdlog::info("floor plan {}: {}", file, parsed.frame);
  {
    // Up to 12 places while they score 98% of the best (a hall of repeated bays).
    GlobalSearchOptions search;
    search.crowd_ratio = 0.98;
    a.global = std::make_shared<GlobalSearchCache>(parsed.plan, search);
  }
  a.id = parsed.plan.id;
  a.digest = FloorPlanDigest(parsed.plan);
  const int64_t t0 = now_ns();
  RouteOptions route;
  route.body_radius_m = config.routes().body_radius_m();
  route.cell_m = config.routes().cell_m() * scale;
  route.snap_m = config.routes().snap_m();
  a.routes = std::make_unique<RoutePlanner>(parsed.plan, route);
  const v1::ExploredConfig& e = config.explored();
  if (e.enabled()) {
    RoomOptions rooms;
    rooms.max_door_m = e.max_door_m();
    rooms.cell_m *= scale;
    ExploredOptions explored;
    explored.cell_m = e.cell_m() * scale;
    explored.max_ray_m = e.max_ray_m();
    explored.min_visit_poses = static_cast<int>(e.min_visit_poses());
    explored.body_radius_m = route.body_radius_m;
    a.explored = std::make_unique<ExploredMap>(
        parsed.plan, std::make_shared<const RoomMap>(parsed.plan, rooms), explored);
  }
  spdlog::info("routes on a {} x {} grid of {:.2f} m, {} rooms, in {:.0f} ms", a.routes->grid().nx,
               a.routes->grid().ny, a.routes->grid().cell_m,
               a.explored ? a.explored->rooms()->rooms().size() : 0,
               static_cast<double>(now_ns() - t0) * 1e-6);
  return a;
}

void PlansInUse::Take(PlanLoad load) {
  floor_ = std::move(load.floor);
  path_ = std::move(load.path);
  follower_.Reset(std::move(load.set));
  others_ = std::move(load.others);
  current_ = std::move(load.assets);
}

void PlansInUse::Clear() {
  current_ = {};
  others_.clear();
  path_.clear();
  follower_.Reset({});
}

bool PlansInUse::ChangeFloor(const FloorEntry& to, double slam_z) {
  const auto next = others_.find(to.id);
  if (next == others_.end()) return false;
  PlanAssets arriving = std::move(next->second);
  others_.erase(next);
  others_[floor_] = std::move(current_);
  current_ = std::move(arriving);
  floor_ = to.id;
  follower_.Changed(to, slam_z);
  return true;
}

}  // namespace floorpose::platform
