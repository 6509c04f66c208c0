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

Engine::Engine(v1::FloorposedConfig configured, Publish publish, std::function<int64_t()> now_ns)
    : config_(std::move(configured)),
      publish_(std::move(publish)),
      now_ns_(std::move(now_ns)),
      frame_(
          ParseHeadsetFrame(config().headset_frame()).value_or(HeadsetFrame::kUnityLeftHandedYUp)),
      wall_options_(ToWallExtractionOptions(config())),
      tracker_(ToMclOptions(config())),
      store_(config().walls().voxel_m()),
      plans_(config().floor()),
      intake_({static_cast<int64_t>(config().limits().max_future_s() * 1e9),
               static_cast<int64_t>(config().limits().restart_gap_s() * 1e9)},
              config().limits().max_future_s(), now_ns_),
      crew_(config().dds().device_id(),
            {config().alerts().motion_m(), config().alerts().pre_alert_s(),
             config().alerts().no_motion_s()},
            publish_),
      jobs_(config().limits().search_cpu()) {}

std::string Engine::Start() {
  if (config().plan_path().empty()) return {};
  const std::string e = LoadPlan(config().plan_path(), config().floor());
  if (!e.empty()) spdlog::error("{}; waiting for a LoadPlan command", e);
  return e;
}

std::string Engine::LoadPlan(const std::string& path, const std::string& floor) {
  return UseLoad(ReadPlan(config(), now_ns_, path, floor));
}

std::string Engine::UseLoad(PlanLoad load) {
  if (!load.error.empty()) {
    intake_.counters().set_plans_refused(intake_.counters().plans_refused() + 1);
    return load.error;
  }
  plans_.Take(std::move(load));
  UsePlan(/*another_floor=*/false);
  return {};
}

void Engine::UsePlan(bool another_floor) {
  PlanAssets& plan = plans_.current();
  if (another_floor)
    tracker_.ChangeFloor(plan.index);
  else
    tracker_.SetPlan(plan.index);
  history_.ForgetLatest();
  // Its explored map at once: the plan's rooms, or the floor as it was left.
  if (plan.explored) plan.explored_sent = plan.explored->revision() - 1;
  PublishExplored();
}

void Engine::FollowFloors(const DecodedPose& pose) {
  const auto change =
      plans_.Follow(pose.pose_slam.z, pose.stamp_ns, config().floors().change_margin_m(),
                    config().floors().change_hold_s());
  if (!change) return;
  const FloorEntry& to = *change->to;
  const std::string left = plans_.floor();
  const size_t dropped = store_.points();
  if (!plans_.ChangeFloor(to, pose.pose_slam.z)) return;  // built with the set: cannot happen
  // The walls in the store are the floor's left behind: registered against this floor's
  // plan they would pull the alignment onto the wrong walls.
  spdlog::info(
      "floor {} -> {}: the headset is at {:.2f} m (floor {} at {:.2f} m); {} wall points "
      "of floor {} dropped",
      left, to.id, change->height_m, to.id, to.height_m, dropped, left);
  store_.Clear();
  UsePlan(/*another_floor=*/true);  // what is published from here on carries the new floor
  intake_.counters().set_floor_changes(intake_.counters().floor_changes() + 1);
  PublishAlignment();
}

void Engine::ExploreWalls(const std::vector<WallPoint>& points) {
  ExploredMap* explored = plans_.current().explored.get();
  const std::optional<v1::PlanPose>& latest = history_.latest();
  if (!explored || !latest || alignment().version == 0 ||
      latest->reliability().flag() != v1::Reliability::RELIABLE)
    return;
  const Se2& T = alignment().T_plan_slam;
  std::vector<Eigen::Vector2d> plan;
  plan.reserve(points.size());
  for (const WallPoint& w : points) plan.push_back(T * w.p.cast<double>());
  explored->AddWalls({latest->x(), latest->y()}, plan);
}

void Engine::PublishExplored() {
  PlanAssets& plan = plans_.current();
  if (!plan.explored || plan.explored->revision() == plan.explored_sent) return;
  plan.explored_sent = plan.explored->revision();
  publish_(Topic::kExplored,
           ToProto(*plan.explored, plan.id, plans_.floor(), intake_.clock().newest_ns()));
}

WallExtractionOptions Engine::BandedWallOptions() const {
  WallExtractionOptions o = wall_options_;
  const double lo = config().walls().min_height_above_eye_m();
  if (const auto eye_z = history_.eye_z(); eye_z && lo > -10) {
    o.min_z = *eye_z + lo;
    o.max_z = *eye_z + config().walls().max_height_above_eye_m();
  }
  return o;
}

bool Engine::TakeStamp(const std::string& what, int64_t* stamp_ns) {
  bool restarted = false;
  if (!intake_.TakeStamp(what, stamp_ns, &restarted)) return false;
  if (restarted) history_.ClearTrack();  // its source stamps are of the old clock
  return true;
}

void Engine::OnMeshDelta(const Envelope& e) {
  if (!Mine(e)) return;  // another wearer's daemon takes it
  intake_.counters().set_mesh_deltas_in(intake_.counters().mesh_deltas_in() + 1);
  DecodedMesh mesh;
  Refusal kind{};
  const std::string error = DecodeMeshDelta(e.payload, frame_, config().limits(), &mesh, &kind);
  if (!error.empty()) return intake_.Reject(kind, error);
  if (!TakeStamp("mesh " + std::to_string(mesh.mesh_id), &mesh.stamp_ns)) return;
  if (mesh.change == v1::MeshDelta::REMOVED) return RemoveMesh(mesh.mesh_id);
  if (OlderThanStored(mesh)) return;
  WallExtractionReport report;
  std::vector<WallPoint> points = ExtractWallPoints({&mesh.vertices, &mesh.triangles}, mesh.mesh_id,
                                                    BandedWallOptions(), &report);
  if (!Extracted(mesh, report)) return;
  StoreWalls(mesh, std::move(points), report);
}

void Engine::RemoveMesh(uint64_t mesh_id) {
  if (store_.Remove(mesh_id)) {
    intake_.counters().set_meshes_removed(intake_.counters().meshes_removed() + 1);
  } else {
    intake_.counters().set_unknown_mesh_ids(intake_.counters().unknown_mesh_ids() + 1);
    intake_.Warn("unknown mesh",
                 "REMOVED for unknown mesh " + std::to_string(mesh_id) + ": ignored");
  }
}

bool Engine::OlderThanStored(const DecodedMesh& mesh) {
  if (const auto stored = store_.MeshStamp(mesh.mesh_id); stored && mesh.stamp_ns < *stored) {
    // A late copy of an older scan: the store has a newer one of the same surface.
    intake_.counters().set_stale_stamps(intake_.counters().stale_stamps() + 1);
    intake_.Warn("stale mesh", "mesh " + std::to_string(mesh.mesh_id) + " " +
                                   v1::MeshDelta::Change_Name(mesh.change) + " of " +
                                   std::to_string(mesh.stamp_ns) +
                                   " ns is older than the stored one (" + std::to_string(*stored) +
                                   " ns): ignored");
    return true;
  }
  return false;
}

bool Engine::Extracted(const DecodedMesh& mesh, const WallExtractionReport& report) {
  if (report.over_limit) {
    intake_.Reject(Refusal::kOverLimits, "mesh " + std::to_string(mesh.mesh_id) + ": " +
                                             std::to_string(report.wall_area_m2) +
                                             " m2 of wall would give more than " +
                                             std::to_string(wall_options_.max_points) + " points");
    return false;
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
  return true;
}

void Engine::StoreWalls(const DecodedMesh& mesh, std::vector<WallPoint> points,
                        const WallExtractionReport& report) {
  const bool known = store_.Contains(mesh.mesh_id);
  if (mesh.change == v1::MeshDelta::UPDATED && !known) {
    // Keep the data: an UPDATED whose ADDED was lost is still a good mesh.
    intake_.counters().set_unknown_mesh_ids(intake_.counters().unknown_mesh_ids() + 1);
    intake_.Warn("unknown mesh",
                 "UPDATED for unknown mesh " + std::to_string(mesh.mesh_id) + ": stored as new");
  }
  const size_t cap = config().limits().max_wall_points();
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
  const std::string error = DecodeHeadsetPose(e.payload, frame_, config().limits(), &pose, &kind);
  if (!error.empty()) return intake_.Reject(kind, error);
  const int64_t source_stamp_ns = pose.stamp_ns;  // as the headset stamped it
  if (!TakeStamp("pose", &pose.stamp_ns)) return;
  const Intake::PoseOrder order = intake_.TakePose(pose.stamp_ns, source_stamp_ns);
  if (order == Intake::PoseOrder::kDuplicate) return;
  if (config_.Use(pose.odometry)) UseOdometry(pose.odometry);
  PlanPoseEstimate est;
  if (order == Intake::PoseOrder::kLate) {
    // Late: answered under the alignment in use, but the walk is not walked backwards.
    est = tracker_.Project(pose.pose_slam);
  } else {
    history_.SetEyeZ(pose.pose_slam.z);
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
  jobs_.AddPosition(pose.stamp_ns, pose.pose_slam.position, tracker_.options().search_window_s);
  history_.Record(pose.pose_slam, out, config().track_history_s());
  publish_(Topic::kPlanPose, out);
  intake_.counters().set_plan_poses_out(intake_.counters().plan_poses_out() + 1);
  if (order == Intake::PoseOrder::kLate) return;  // not where the wearer is
  history_.SetLatest(out);
  crew_.Watch(pose.stamp_ns, pose.pose_slam, plans_.floor(), out);
  PlanAssets& plan = plans_.current();
  if (plan.explored) {
    if (out.reliability().flag() == v1::Reliability::RELIABLE && out.alignment_version() > 0)
      plan.explored->AddVisit({out.x(), out.y()});
    if (pose.stamp_ns >= plan.next_explored_ns) {
      PublishExplored();
      plan.next_explored_ns =
          pose.stamp_ns + static_cast<int64_t>(config().explored().publish_period_s() * 1e9);
    }
  }
}

void Engine::UseOdometry(v1::HeadsetPose::Odometry odometry) {
  const tracking::MclOptions o = ToMclOptions(config());
  tracker_.SetDrift(o.motion, o.window_s);
  spdlog::info(
      "device {} moves on {} odometry: heading drift {:.2f} deg/sqrt(m), {:.3f} per turn, "
      "window {} s",
      config().dds().device_id(), v1::HeadsetPose::Odometry_Name(odometry),
      o.motion.heading_rad_per_sqrt_m * 180 / M_PI, o.motion.heading_per_turn, o.window_s);
}

v1::PlanPose Engine::ToPlanPose(const PlanPoseEstimate& est, int64_t stamp_ns) const {
  v1::PlanPose out;
  out.set_source_stamp_ns(stamp_ns);
  out.set_x(est.pose.position.x());
  out.set_y(est.pose.position.y());
  out.set_heading(est.pose.heading);
  out.set_height(est.pose.z);
  out.set_floor(plans_.floor());
  out.set_alignment_version(est.alignment_version);
  *out.mutable_reliability() = ToProto(est.reliability);
  return out;
}

void Engine::PublishTrack() {
  if (const auto track = history_.Track(alignment(), plans_.floor()))
    publish_(Topic::kPlanTrack, *track);
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

// Command.wall_pick in the SLAM frame: the headset's side converted from its convention.
WallPick PickInSlam(const v1::Command::WallPick& p, HeadsetFrame frame) {
  const Eigen::Vector3d point =
      PointToSlam(frame, {p.headset_point().x(), p.headset_point().y(), p.headset_point().z()});
  const Eigen::Vector3d normal =
      PointToSlam(frame, {p.headset_normal().x(), p.headset_normal().y(), p.headset_normal().z()});
  return {point.head<2>(),
          normal.head<2>(),
          {p.plan_x(), p.plan_y()},
          {p.plan_normal_x(), p.plan_normal_y()}};
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
      case v1::Command::kLoadPlan:
        error = StartLoadPlan(cmd, reply);
        if (error.empty()) return;  // answered once the plan is built
        break;
      case v1::Command::kWallPick:
        error = tracker_.ApplyWallPick(PickInSlam(cmd.wall_pick(), frame_),
                                       intake_.clock().newest_ns());
        if (error.empty()) done = "wall pick applied";
        break;
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
        for (std::string& id : ListPlanIds(config().plan_dir())) reply.add_plans(std::move(id));
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
        if (!crew_.Acknowledge(cmd.acknowledge_alert().by(), history_.latest()))
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

std::string Engine::StartLoadPlan(const v1::Command& cmd, const v1::CommandReply& reply) {
  const auto& load = cmd.load_plan();
  std::string path = load.path();
  std::string error;
  if (!load.plan_id().empty() && !load.path().empty())
    error = "give plan_id or path, not both";
  else if (load.plan_id().empty() && load.path().empty())
    error = "load_plan without plan_id or path";
  else if (!load.plan_id().empty())
    FindPlanFile(config().plan_dir(), load.plan_id(), &path, &error);
  else if (plan_loading_)
    error = "another plan is loading: try again when it is answered";
  if (!error.empty()) return error;
  const std::string floor = load.floor().empty() ? config().floor() : load.floor();
  // Read and built elsewhere; the poses meanwhile go on on the plan in use.
  auto built = std::make_shared<PlanLoad>();
  auto finish = [this, built, cmd, reply, path] {
    plan_loading_ = false;
    const std::string refused = UseLoad(std::move(*built));
    if (refused.empty()) store_.TakeNewPoints();  // the store is kept: the same walls
    FinishCommand(cmd, reply, refused, refused.empty() ? "plan loaded: " + path : "");
  };
  auto work = [built, config = config(), now = now_ns_, path, floor] {
    *built = ReadPlan(config, now, path, floor);
  };
  if (!offload_) {
    work();
    finish();
    return "";
  }
  plan_loading_ = true;
  offload_(std::move(work), std::move(finish));
  return "";
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
      history_.ClearTrack();  // that track belonged to the old alignment or plan
    PublishTrack();
  }
  *reply.mutable_status() = Status(prefix + (error.empty() ? done : "refused: " + error));
  publish_(Topic::kStatus, reply.status());
  publish_(Topic::kCommandReply, reply);
}

void Engine::PublishAlignment() {
  publish_(Topic::kAlignment, ToProto(alignment(), plans_.floor()));
}

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
  if (const auto& last = jobs_.last()) {
    *s.mutable_last_registration() = ToProto(last->result);
    s.mutable_last_registration()->set_accepted(last->accepted);
    if (!last->accepted) s.mutable_last_registration()->set_reason(last->why);
  }
  s.set_alignment_version(alignment().version);
  s.set_stamp_ns(now_ns_());
  s.set_message(message);
  *s.mutable_reliability() = ToProto(reliability());
  *s.mutable_alert() = crew_.AlertMessage(history_.latest());
  return s;
}

std::string Engine::StatusLine() const {
  return std::string(ToString(state())) + ", " + std::to_string(store_.points()) +
         " wall points, " + std::to_string(intake_.counters().plan_poses_out()) + " plan poses";
}

}  // namespace floorpose::platform
