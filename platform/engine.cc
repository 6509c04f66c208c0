#include "platform/engine.h"

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "platform/codec.h"
#include "platform/config.h"
#include "platform/explored_codec.h"
#include "platform/floor_plan_io.h"

namespace floorpose::platform {

Engine::Engine(v1::FloorposedConfig config, Publish publish, std::function<int64_t()> now_ns)
    : base_config_(std::move(config)),
      config_(base_config_),
      publish_(std::move(publish)),
      now_ns_(std::move(now_ns)),
      frame_(
          ParseHeadsetFrame(config_.headset_frame()).value_or(HeadsetFrame::kUnityLeftHandedYUp)),
      wall_options_(ToWallExtractionOptions(config_)),
      tracker_(ToMclOptions(config_)),
      store_(config_.walls().voxel_m()),
      floor_(config_.floor()),
      intake_({static_cast<int64_t>(config_.limits().max_future_s() * 1e9),
               static_cast<int64_t>(config_.limits().restart_gap_s() * 1e9)},
              config_.limits().max_future_s(), now_ns_),
      crew_(config_.dds().device_id(),
            {config_.alerts().motion_m(), config_.alerts().pre_alert_s(),
             config_.alerts().no_motion_s()},
            publish_) {}

std::string Engine::Start() {
  if (config_.plan_path().empty()) return {};
  const std::string e = LoadPlan(config_.plan_path(), config_.floor());
  if (!e.empty()) spdlog::error("{}; waiting for a LoadPlan command", e);
  return e;
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
// parents), rooms and explored maps 8 each, the closest-wall index 8 (cells and lists).
double PlanGridScale(const FloorPlan& plan, const v1::FloorposedConfig& c) {
  const Eigen::Vector2d extent = (plan.max - plan.min).array() + 2.0;  // the grids' margins
  auto per_m2 = [](double bytes_per_cell, double cell_m) {
    return bytes_per_cell / (cell_m * cell_m);
  };
  const double bytes =
      extent.x() * extent.y() *
      (per_m2(20, c.routes().cell_m()) + per_m2(8, RoomOptions{}.cell_m) +
       per_m2(8, c.explored().cell_m()) + per_m2(8, ClosestWallIndex::Options{}.cell_m));
  const double budget = static_cast<double>(c.limits().max_plan_memory_mb()) * (1 << 20);
  return std::max(1.0, std::sqrt(bytes / budget));
}

}  // namespace

std::string Engine::LoadPlan(const std::string& path, const std::string& floor) {
  return UseLoad(ReadPlan(config_, now_ns_, path, floor));
}

Engine::PlanLoad Engine::ReadPlan(const v1::FloorposedConfig& config,
                                  const std::function<int64_t()>& now_ns, const std::string& path,
                                  const std::string& floor) {
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

std::string Engine::UseLoad(PlanLoad load) {
  if (!load.error.empty()) {
    intake_.counters().set_plans_refused(intake_.counters().plans_refused() + 1);
    return load.error;
  }
  floor_ = load.floor;
  plan_path_ = load.path;
  floors_.Reset(std::move(load.set));
  other_floors_ = std::move(load.others);
  UsePlan(std::move(load.assets), /*another_floor=*/false);
  return {};
}

Engine::PlanAssets Engine::BuildPlan(const v1::FloorposedConfig& config,
                                     const std::function<int64_t()>& now_ns,
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
  index_options.max_distance_m = std::max(3.0, config.icp().max_correspondence_m());
  a.index = std::make_shared<const ClosestWallIndex>(parsed.plan, index_options);
  spdlog::info("floor plan {}: {} segments ({} dropped), {:.1f} x {:.1f} m, index {:.1f} MB", file,
               parsed.plan.segments.size(), parsed.dropped_segments,
               parsed.plan.max.x() - parsed.plan.min.x(), parsed.plan.max.y() - parsed.plan.min.y(),
               static_cast<double>(a.index->MemoryBytes()) / 1e6);
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

void Engine::UsePlan(PlanAssets assets, bool another_floor) {
  plan_ = std::move(assets);
  if (another_floor)
    tracker_.ChangeFloor(plan_.index);
  else
    tracker_.SetPlan(plan_.index);
  last_plan_pose_.reset();
  // Its explored map at once: the plan's rooms, or the floor as it was left.
  if (plan_.explored) explored_sent_ = plan_.explored->revision() - 1;
  PublishExplored();
}

void Engine::FollowFloors(const DecodedPose& pose) {
  const auto change =
      floors_.Observe(floor_, pose.pose_slam.z, pose.stamp_ns, config_.floors().change_margin_m(),
                      config_.floors().change_hold_s());
  if (change) ChangeFloor(*change->to, pose.pose_slam.z, change->height_m);
}

void Engine::ChangeFloor(const FloorEntry& to, double slam_z, double height_m) {
  const auto next = other_floors_.find(to.id);
  if (next == other_floors_.end()) return;  // built with the set: cannot happen
  // The walls in the store are the floor's left behind: registered against this floor's
  // plan they would pull the alignment onto the wrong walls.
  spdlog::info(
      "floor {} -> {}: the headset is at {:.2f} m (floor {} at {:.2f} m); {} wall points "
      "of floor {} dropped",
      floor_, to.id, height_m, to.id, to.height_m, store_.points(), floor_);
  store_.Clear();
  PlanAssets arriving = std::move(next->second);
  other_floors_.erase(next);
  other_floors_[floor_] = std::move(plan_);
  floor_ = to.id;  // what is published from here on carries it
  UsePlan(std::move(arriving), /*another_floor=*/true);
  floors_.Changed(to, slam_z);
  intake_.counters().set_floor_changes(intake_.counters().floor_changes() + 1);
  PublishAlignment();
}

void Engine::ExploreWalls(const std::vector<WallPoint>& points) {
  if (!plan_.explored || !last_plan_pose_ || alignment().version == 0 ||
      last_plan_pose_->reliability().flag() != v1::Reliability::RELIABLE)
    return;
  const Se2& T = alignment().T_plan_slam;
  std::vector<Eigen::Vector2d> plan;
  plan.reserve(points.size());
  for (const WallPoint& w : points) plan.push_back(T * w.p.cast<double>());
  plan_.explored->AddWalls({last_plan_pose_->x(), last_plan_pose_->y()}, plan);
}

void Engine::PublishExplored() {
  if (!plan_.explored || plan_.explored->revision() == explored_sent_) return;
  explored_sent_ = plan_.explored->revision();
  publish_(Topic::kExplored,
           ToProto(*plan_.explored, plan_.id, floor_, intake_.clock().newest_ns()));
}

WallExtractionOptions Engine::BandedWallOptions() const {
  WallExtractionOptions o = wall_options_;
  const double lo = config_.walls().min_height_above_eye_m();
  if (eye_z_ && lo > -10) {
    o.min_z = *eye_z_ + lo;
    o.max_z = *eye_z_ + config_.walls().max_height_above_eye_m();
  }
  return o;
}

bool Engine::TakeStamp(const std::string& what, int64_t* stamp_ns) {
  bool restarted = false;
  if (!intake_.TakeStamp(what, stamp_ns, &restarted)) return false;
  if (restarted) recent_.clear();  // its source stamps are of the old clock
  return true;
}

void Engine::OnMeshDelta(const Envelope& e) {
  if (!Mine(e)) return;  // another wearer's daemon takes it
  intake_.counters().set_mesh_deltas_in(intake_.counters().mesh_deltas_in() + 1);
  DecodedMesh mesh;
  Refusal kind{};
  const std::string error = DecodeMeshDelta(e.payload, frame_, config_.limits(), &mesh, &kind);
  if (!error.empty()) return intake_.Reject(kind, error);
  if (!TakeStamp("mesh " + std::to_string(mesh.mesh_id), &mesh.stamp_ns)) return;
  if (mesh.change == v1::MeshDelta::REMOVED) {
    if (store_.Remove(mesh.mesh_id)) {
      intake_.counters().set_meshes_removed(intake_.counters().meshes_removed() + 1);
    } else {
      intake_.counters().set_unknown_mesh_ids(intake_.counters().unknown_mesh_ids() + 1);
      intake_.Warn("unknown mesh",
                   "REMOVED for unknown mesh " + std::to_string(mesh.mesh_id) + ": ignored");
    }
    return;
  }
  if (const auto stored = store_.MeshStamp(mesh.mesh_id); stored && mesh.stamp_ns < *stored) {
    // A late copy of an older scan: the store has a newer one of the same surface.
    intake_.counters().set_stale_stamps(intake_.counters().stale_stamps() + 1);
    intake_.Warn("stale mesh", "mesh " + std::to_string(mesh.mesh_id) + " " +
                                   v1::MeshDelta::Change_Name(mesh.change) + " of " +
                                   std::to_string(mesh.stamp_ns) +
                                   " ns is older than the stored one (" + std::to_string(*stored) +
                                   " ns): ignored");
    return;
  }
  WallExtractionReport report;
  std::vector<WallPoint> points = ExtractWallPoints({&mesh.vertices, &mesh.triangles}, mesh.mesh_id,
                                                    BandedWallOptions(), &report);
  if (report.over_limit) {
    return intake_.Reject(Refusal::kOverLimits, "mesh " + std::to_string(mesh.mesh_id) + ": " +
                                                    std::to_string(report.wall_area_m2) +
                                                    " m2 of wall would give more than " +
                                                    std::to_string(wall_options_.max_points) +
                                                    " points");
  }
  if (report.bad_indices || report.degenerate_triangles || mesh.unusable_vertices) {
    auto& c = intake_.counters();
    c.set_bad_index_triangles(c.bad_index_triangles() + report.bad_indices);
    c.set_degenerate_triangles(c.degenerate_triangles() + report.degenerate_triangles);
    c.set_unusable_vertices(c.unusable_vertices() + mesh.unusable_vertices);
    intake_.Warn("dropped triangles",
                 "mesh " + std::to_string(mesh.mesh_id) + ": dropped " +
                     std::to_string(report.bad_indices) + " triangles with bad indices, " +
                     std::to_string(report.degenerate_triangles) + " degenerate; " +
                     std::to_string(mesh.unusable_vertices) + " unusable vertices");
  }
  const bool known = store_.Contains(mesh.mesh_id);
  if (mesh.change == v1::MeshDelta::UPDATED && !known) {
    // Keep the data: an UPDATED whose ADDED was lost is still a good mesh.
    intake_.counters().set_unknown_mesh_ids(intake_.counters().unknown_mesh_ids() + 1);
    intake_.Warn("unknown mesh",
                 "UPDATED for unknown mesh " + std::to_string(mesh.mesh_id) + ": stored as new");
  }
  const size_t cap = config_.limits().max_wall_points();
  if (points.size() > cap)
    return intake_.Reject(Refusal::kOverLimits,
                          "mesh " + std::to_string(mesh.mesh_id) + ": " +
                              std::to_string(points.size()) +
                              " wall points, more than limits.max_wall_points");
  // At the cap the meshes scanned longest ago make room (WallStore::EvictOldest).
  const size_t replaced = known ? store_.MeshPoints(mesh.mesh_id) : 0;
  if (const size_t evicted = store_.EvictOldest(cap - points.size() + replaced, mesh.mesh_id)) {
    intake_.counters().set_meshes_evicted(intake_.counters().meshes_evicted() + evicted);
    intake_.Warn("evicted", "wall-point store at limits.max_wall_points (" + std::to_string(cap) +
                                "): the " + std::to_string(evicted) +
                                " meshes scanned longest ago evicted for mesh " +
                                std::to_string(mesh.mesh_id));
  }
  ExploreWalls(points);
  const size_t extracted = points.size();
  store_.Upsert(mesh.mesh_id, std::move(points), mesh.stamp_ns);
  if (mesh.change == v1::MeshDelta::ADDED && !known)
    intake_.counters().set_meshes_added(intake_.counters().meshes_added() + 1);
  else
    intake_.counters().set_meshes_updated(intake_.counters().meshes_updated() + 1);
  spdlog::debug(
      "mesh {} {}: {} wall points ({} of {} triangles vertical, {} points outside the height "
      "band); store {} points in {} meshes",
      mesh.mesh_id, v1::MeshDelta::Change_Name(mesh.change), extracted, report.vertical_triangles,
      report.triangles, report.outside_band, store_.points(), store_.meshes());
}

void Engine::OnHeadsetPose(const Envelope& e) {
  if (!Mine(e)) return;
  intake_.counters().set_poses_in(intake_.counters().poses_in() + 1);
  DecodedPose pose;
  Refusal kind{};
  const std::string error = DecodeHeadsetPose(e.payload, frame_, config_.limits(), &pose, &kind);
  if (!error.empty()) return intake_.Reject(kind, error);
  const int64_t source_stamp_ns = pose.stamp_ns;  // as the headset stamped it
  if (!TakeStamp("pose", &pose.stamp_ns)) return;
  const Intake::PoseOrder order = intake_.TakePose(pose.stamp_ns, source_stamp_ns);
  if (order == Intake::PoseOrder::kDuplicate) return;
  if (pose.odometry != odometry_) UseOdometry(pose.odometry);
  PlanPoseEstimate est;
  if (order == Intake::PoseOrder::kLate) {
    // Late: answered under the alignment in use, but the walk is not walked backwards.
    est = tracker_.Project(pose.pose_slam);
  } else {
    eye_z_ = pose.pose_slam.z;
    FollowFloors(pose);
    if (pose.tracking == v1::HeadsetPose::TRACKING_LOST) {
      tracker_.LoseTracking();
      est = tracker_.Project(pose.pose_slam);
    } else {
      est = tracker_.Correct(pose.pose_slam, pose.stamp_ns);
    }
  }
  if (!tracker_.has_plan()) {
    intake_.counters().set_poses_without_plan(intake_.counters().poses_without_plan() + 1);
    intake_.Warn("no plan",
                 "pose before a floor plan is loaded: answered in slam coordinates, "
                 "UNRELIABLE");
  }
  if (pose.tracking == v1::HeadsetPose::TRACKING_LOST) {
    // The headset itself does not know where it is: neither do we.
    est.reliability.flag = ReliabilityFlag::kUnreliable;
    est.reliability.probability = 0.0;
    est.reliability.reason = "headset tracking lost";
  }
  const v1::PlanPose out = ToPlanPose(est, source_stamp_ns);
  searches_.AddPosition(pose.stamp_ns, pose.pose_slam.position, tracker_.options().search_window_s);
  if (config_.track_history_s() > 0) {
    recent_.emplace_back(pose.pose_slam, out);
    const auto horizon = static_cast<int64_t>(config_.track_history_s() * 1e9);
    while (!recent_.empty() && recent_.front().second.source_stamp_ns() < source_stamp_ns - horizon)
      recent_.pop_front();
  }
  publish_(Topic::kPlanPose, out);
  intake_.counters().set_plan_poses_out(intake_.counters().plan_poses_out() + 1);
  if (order == Intake::PoseOrder::kLate) return;  // not where the wearer is
  last_plan_pose_ = out;
  crew_.Watch(pose.stamp_ns, pose.pose_slam, floor_, out);
  if (plan_.explored) {
    if (out.reliability().flag() == v1::Reliability::RELIABLE && out.alignment_version() > 0)
      plan_.explored->AddVisit({out.x(), out.y()});
    if (pose.stamp_ns >= next_explored_ns_) {
      PublishExplored();
      next_explored_ns_ =
          pose.stamp_ns + static_cast<int64_t>(config_.explored().publish_period_s() * 1e9);
    }
  }
}

void Engine::UseOdometry(v1::HeadsetPose::Odometry odometry) {
  odometry_ = odometry;
  config_ = ForOdometry(base_config_, odometry);
  const tracking::MclOptions o = ToMclOptions(config_);
  tracker_.SetDrift(o.motion, o.window_s);
  spdlog::info(
      "device {} moves on {} odometry: heading drift {:.2f} deg/sqrt(m), {:.3f} per turn, "
      "window {} s",
      config_.dds().device_id(), v1::HeadsetPose::Odometry_Name(odometry),
      o.motion.heading_rad_per_sqrt_m * 180 / M_PI, o.motion.heading_per_turn, o.window_s);
}

v1::PlanPose Engine::ToPlanPose(const PlanPoseEstimate& est, int64_t stamp_ns) const {
  v1::PlanPose out;
  out.set_source_stamp_ns(stamp_ns);
  out.set_x(est.pose.position.x());
  out.set_y(est.pose.position.y());
  out.set_heading(est.pose.heading);
  out.set_height(est.pose.z);
  out.set_floor(floor_);
  out.set_alignment_version(est.alignment_version);
  *out.mutable_reliability() = ToProto(est.reliability);
  return out;
}

void Engine::PublishTrack() {
  if (recent_.empty() || alignment().version == 0) return;
  v1::PlanTrack track;
  const AlignmentState& a = alignment();
  track.set_alignment_version(a.version);
  track.set_floor(floor_);
  for (const auto& [slam, published] : recent_) {
    v1::PlanPose* p = track.add_poses();
    *p = published;
    const Pose2 plan = Apply(a.T_plan_slam, slam);
    p->set_x(plan.position.x());
    p->set_y(plan.position.y());
    p->set_heading(plan.heading);
    p->set_alignment_version(a.version);
  }
  publish_(Topic::kPlanTrack, track);
}

namespace {

const char* CommandName(v1::Command::CommandCase c) {
  switch (c) {
    case v1::Command::kLoadPlan: return "load_plan";
    case v1::Command::kWallPick: return "wall_pick";
    case v1::Command::kFlip: return "flip";
    case v1::Command::kReset: return "reset";
    case v1::Command::kGetState: return "get_state";
    case v1::Command::kRoute: return "route";
    case v1::Command::kPlaceMarker: return "place_marker";
    case v1::Command::kAcknowledgeAlert: return "acknowledge_alert";
    case v1::Command::kGetTeammates: return "get_teammates";
    case v1::Command::COMMAND_NOT_SET: break;
  }
  return "";
}

}  // namespace

void Engine::OnCommand(const Envelope& e) {
  if (!Mine(e)) return;
  intake_.counters().set_commands_in(intake_.counters().commands_in() + 1);
  v1::Command cmd;
  std::string error = DecodeCommand(e.payload, &cmd);
  v1::CommandReply reply;
  reply.set_request_id(cmd.request_id());
  reply.set_command(CommandName(cmd.command_case()));
  std::string done;
  if (error.empty()) {
    switch (cmd.command_case()) {
      case v1::Command::kLoadPlan: {
        const auto& load = cmd.load_plan();
        std::string path = load.path();
        if (!load.plan_id().empty() && !load.path().empty())
          error = "give plan_id or path, not both";
        else if (load.plan_id().empty() && load.path().empty())
          error = "load_plan without plan_id or path";
        else if (!load.plan_id().empty())
          FindPlanFile(config_.plan_dir(), load.plan_id(), &path, &error);
        else if (plan_loading_)
          error = "another plan is loading: try again when it is answered";
        if (!error.empty()) break;
        const std::string floor = load.floor().empty() ? config_.floor() : load.floor();
        // Read and built elsewhere; the poses meanwhile go on on the plan in use.
        auto built = std::make_shared<PlanLoad>();
        auto finish = [this, built, cmd, reply, path] {
          plan_loading_ = false;
          const std::string refused = UseLoad(std::move(*built));
          if (refused.empty()) store_.TakeNewPoints();  // the store is kept: the same walls
          FinishCommand(cmd, reply, refused, refused.empty() ? "plan loaded: " + path : "");
        };
        auto work = [built, config = config_, now = now_ns_, path, floor] {
          *built = ReadPlan(config, now, path, floor);
        };
        if (!offload_) {
          work();
          return finish();
        }
        plan_loading_ = true;
        return offload_(std::move(work), std::move(finish));
      }
      case v1::Command::kWallPick: {
        const auto& p = cmd.wall_pick();
        const Eigen::Vector3d point = PointToSlam(
            frame_, {p.headset_point().x(), p.headset_point().y(), p.headset_point().z()});
        const Eigen::Vector3d normal = PointToSlam(
            frame_, {p.headset_normal().x(), p.headset_normal().y(), p.headset_normal().z()});
        WallPick pick{point.head<2>(),
                      normal.head<2>(),
                      {p.plan_x(), p.plan_y()},
                      {p.plan_normal_x(), p.plan_normal_y()}};
        error = tracker_.ApplyWallPick(pick, intake_.clock().newest_ns());
        if (error.empty()) done = "wall pick applied";
        break;
      }
      case v1::Command::kFlip:
        error = tracker_.Flip(intake_.clock().newest_ns());
        if (error.empty()) done = "flipped";
        break;
      case v1::Command::kReset:
        tracker_.Reset();
        store_.Clear();
        intake_.clock().Reset();
        crew_.Reset();
        done = "reset: alignment, wall store, way back and the headset's clock cleared";
        break;
      case v1::Command::kGetState:
        for (std::string& id : ListPlanIds(config_.plan_dir())) reply.add_plans(std::move(id));
        done = "state";
        break;
      case v1::Command::kRoute: {
        error = PlanRoute(cmd.route(), reply.mutable_route());
        if (error.empty()) {
          const v1::RouteReply& r = reply.route();
          const v1::PlanPoint& to = r.path(r.path_size() - 1);
          done = fmt::format("route of {:.1f} m in {} legs to ({:.2f}, {:.2f})", r.length_m(),
                             r.path_size() - 1, to.x(), to.y());
        } else {
          reply.clear_route();
        }
        break;
      }
      case v1::Command::kPlaceMarker:
        error = PlaceMarker(cmd.place_marker(), reply.mutable_marker());
        if (error.empty()) {
          done = fmt::format("marker {} placed at ({:.2f}, {:.2f})", reply.marker().id(),
                             reply.marker().x(), reply.marker().y());
        }
        break;
      case v1::Command::kAcknowledgeAlert:
        if (!crew_.Acknowledge(cmd.acknowledge_alert().by(), last_plan_pose_))
          error = "no alert to acknowledge";
        else
          done = "alert acknowledged";
        break;
      case v1::Command::kGetTeammates:
        for (v1::Teammate& t : crew_.Teammates(now_ns_())) *reply.add_teammates() = std::move(t);
        done = fmt::format("{} teammates", reply.teammates_size());
        break;
      case v1::Command::COMMAND_NOT_SET: break;
    }
  }
  FinishCommand(cmd, std::move(reply), error, done);
}

void Engine::FinishCommand(const v1::Command& cmd, v1::CommandReply reply, const std::string& error,
                           const std::string& done) {
  const std::string prefix = "request " + std::to_string(cmd.request_id()) + ": ";
  reply.set_ok(error.empty());
  reply.set_message(error.empty() ? done : error);
  if (!error.empty()) {
    intake_.counters().set_commands_refused(intake_.counters().commands_refused() + 1);
    intake_.Warn("command refused", "command refused: " + prefix + error);
  } else if (cmd.command_case() == v1::Command::kLoadPlan ||
             cmd.command_case() == v1::Command::kWallPick ||
             cmd.command_case() == v1::Command::kFlip ||
             cmd.command_case() == v1::Command::kReset) {
    spdlog::info("command: {}{}", prefix, done);
    // Always: after a reset or a new plan, version 0 tells late joiners the old one is void.
    PublishAlignment();
    if (cmd.command_case() == v1::Command::kReset || cmd.command_case() == v1::Command::kLoadPlan)
      recent_.clear();  // that track belonged to the old alignment or plan
    PublishTrack();
  }
  *reply.mutable_status() = Status(prefix + (error.empty() ? done : "refused: " + error));
  publish_(Topic::kStatus, reply.status());
  publish_(Topic::kCommandReply, reply);
}

void Engine::PublishAlignment() { publish_(Topic::kAlignment, ToProto(alignment(), floor_)); }

void Engine::PublishStatus(const std::string& message) {
  publish_(Topic::kStatus, Status(message));
}

v1::DaemonStatus Engine::Status(const std::string& message) const {
  v1::DaemonStatus s;
  s.set_state(ToProto(state()));
  s.set_plan_id(tracker_.has_plan() ? tracker_.index()->plan().id : "");
  s.set_live_meshes(store_.meshes());
  s.set_wall_points(store_.points());
  *s.mutable_counters() = intake_.counters();
  if (last_registration_) {
    *s.mutable_last_registration() = ToProto(last_registration_->result);
    s.mutable_last_registration()->set_accepted(last_registration_->accepted);
    if (!last_registration_->accepted)
      s.mutable_last_registration()->set_reason(last_registration_->why);
  }
  s.set_alignment_version(alignment().version);
  s.set_stamp_ns(now_ns_());
  s.set_message(message);
  *s.mutable_reliability() = ToProto(reliability());
  *s.mutable_alert() = crew_.AlertMessage(last_plan_pose_);
  return s;
}

std::string Engine::StatusLine() const {
  return std::string(ToString(state())) + ", " + std::to_string(store_.points()) +
         " wall points, " + std::to_string(intake_.counters().plan_poses_out()) + " plan poses";
}

}  // namespace floorpose::platform
