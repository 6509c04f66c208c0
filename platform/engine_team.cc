// Engine (platform/engine.h): what it does for the team beyond the wearer's own pose:
// routes (to a point, the way out, the way back), markers, the no-motion alert and the
// teammates.
#include <spdlog/spdlog.h>

#include <cmath>

#include "platform/clock.h"
#include "platform/engine.h"

namespace floorpose::platform {

namespace {

// BACKTRACK's waypoints: a crumb every this far along the way back (the legs between them
// are routes of their own, pulled tight, so the way back keeps the walk's doors without
// its wiggles).
constexpr double kBacktrackWaypointM = 3.0;

v1::Alert::Kind ToProto(NoMotionAlarm::Level level) {
  switch (level) {
    case NoMotionAlarm::Level::kPreAlert: return v1::Alert::PRE_ALERT;
    case NoMotionAlarm::Level::kAlert: return v1::Alert::NO_MOTION;
    case NoMotionAlarm::Level::kNone: break;
  }
  return v1::Alert::NONE;
}

}  // namespace

void Engine::WatchWearer(const DecodedPose& pose) {
  crumbs_.Add(pose.pose_slam.position, floor_);
  const Eigen::Vector3d head(pose.pose_slam.position.x(), pose.pose_slam.position.y(),
                             pose.pose_slam.z);
  const NoMotionAlarm::Level before = alarm_.level();
  if (!alarm_.Update(pose.stamp_ns, head)) return;
  if (alarm_.level() == NoMotionAlarm::Level::kAlert && before != alarm_.level())
    spdlog::warn("ALERT: {} has not moved for {:.0f} s", config_.dds().device_id(),
                 alarm_.still_s());
  publish_(Topic::kAlert, AlertMessage());
}

v1::Alert Engine::AlertMessage() const {
  v1::Alert a;
  a.set_kind(ToProto(alarm_.level()));
  a.set_still_s(alarm_.still_s());
  a.set_since_stamp_ns(alarm_.still_since_ns());
  a.set_acknowledged(alarm_.acknowledged());
  a.set_acknowledged_by(alarm_.acknowledged_by());
  if (last_plan_pose_) *a.mutable_pose() = *last_plan_pose_;
  return a;
}

std::optional<Eigen::Vector2d> Engine::EntryOnPlan() const {
  const std::vector<Eigen::Vector2d> back = crumbs_.WayBackOn(floor_);
  if (back.empty()) return std::nullopt;
  return alignment().T_plan_slam * back.back();
}

std::string Engine::PlanRoute(const v1::Command::Route& request, v1::RouteReply* reply) {
  if (!plan_.routes) return "no floor plan";
  if (!last_plan_pose_ || last_plan_pose_->alignment_version() == 0)
    return "no position on the plan yet";
  const int64_t t0 = now_ns_();
  const Eigen::Vector2d from(last_plan_pose_->x(), last_plan_pose_->y());
  const std::vector<KeepOut> keep_out = markers_.KeepOuts(plan_.id, floor_);
  const std::optional<Eigen::Vector2d> entry = EntryOnPlan();
  Route route;
  switch (request.destination()) {
    case v1::Command::Route::EXIT:
      if (!plan_.routes->exits().empty()) {
        route = plan_.routes->WayOut(from, keep_out);
      } else if (entry) {
        route = plan_.routes->Plan(from, *entry, keep_out);
      } else {
        route.error = "the plan marks no exit and no stairs, and the wearer's entry is not known";
      }
      break;
    case v1::Command::Route::BACKTRACK: {
      if (!entry) return "no way back: no path walked on this floor yet";
      std::vector<Eigen::Vector2d> via;
      Eigen::Vector2d last = from;
      for (const Eigen::Vector2d& slam : crumbs_.WayBackOn(floor_)) {
        const Eigen::Vector2d p = alignment().T_plan_slam * slam;
        if ((p - last).norm() < kBacktrackWaypointM) continue;
        via.push_back(p);
        last = p;
      }
      if (!via.empty() && (via.back() - *entry).norm() < kBacktrackWaypointM) via.pop_back();
      route = plan_.routes->Through(from, via, *entry, keep_out);
      break;
    }
    default: route = plan_.routes->Plan(from, {request.to_x(), request.to_y()}, keep_out); break;
  }
  if (!route.ok()) return route.error;
  for (const Eigen::Vector2d& p : route.path) {
    v1::PlanPoint* point = reply->add_path();
    point->set_x(p.x());
    point->set_y(p.y());
  }
  reply->set_length_m(route.length_m);
  reply->set_goal_moved_m(route.goal_moved_m);
  *reply->mutable_from_reliability() = last_plan_pose_->reliability();
  reply->set_time_ms(static_cast<double>(now_ns_() - t0) * 1e-6);
  return {};
}

std::string Engine::PlaceMarker(const v1::Command::PlaceMarker& request, v1::Marker* marker) {
  if (!tracker_.has_plan()) return "no floor plan";
  if (alignment().version == 0) return "no alignment yet: the gaze point has no place on the plan";
  if (request.kind() == v1::Marker::KIND_UNSPECIFIED || !v1::Marker::Kind_IsValid(request.kind()))
    return "marker kind missing or unknown";
  const auto& h = request.headset_point();
  const Eigen::Vector3d slam = PointToSlam(frame_, {h.x(), h.y(), h.z()});
  if (!slam.allFinite() || slam.cwiseAbs().maxCoeff() > config_.limits().max_abs_coordinate_m())
    return "gaze point not finite or out of range";
  const Eigen::Vector2d p = alignment().T_plan_slam * slam.head<2>();
  const int64_t now = WallClockNs();
  marker->set_id(fmt::format("{}-{}", config_.dds().device_id(), now / 1'000'000));
  marker->set_kind(request.kind());
  marker->set_plan_id(plan_.id);
  marker->set_floor(floor_);
  marker->set_x(p.x());
  marker->set_y(p.y());
  marker->set_radius_m(request.radius_m());
  marker->set_text(request.text().substr(0, 1024));
  marker->set_author(config_.dds().device_id());
  marker->set_created_unix_ns(now);
  marker->set_revision(1);
  if (last_plan_pose_) *marker->mutable_placed_from() = last_plan_pose_->reliability();
  std::string why;
  if (markers_.Merge(*marker, &why) == MarkerBoard::Take::kRefused) return why;
  return {};
}

void Engine::OnTeam(Topic topic, const Envelope& e) {
  if (topic != Topic::kMarker) {
    roster_.Take(topic, e, now_ns_());
    return;
  }
  v1::Marker marker;
  if (!marker.ParseFromString(e.payload)) {
    Warn("marker", "marker from " + e.device_id.substr(0, 64) + " is not a Marker protobuf");
    return;
  }
  std::string why;
  switch (markers_.Merge(marker, &why)) {
    case MarkerBoard::Take::kRefused: Warn("marker", "marker refused: " + why); return;
    case MarkerBoard::Take::kKnown: return;
    case MarkerBoard::Take::kNew:
    case MarkerBoard::Take::kReplaced:
      publish_(Topic::kMarker, marker);  // held for those who join later
      return;
  }
}

void Engine::PublishMarkers() {
  for (const auto& [id, m] : markers_.markers()) publish_(Topic::kMarker, m);
}

}  // namespace floorpose::platform
