#include "platform/crew.h"

#include <spdlog/spdlog.h>

#include "platform/clock.h"

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

Crew::Crew(std::string device_id, const NoMotionOptions& alarm, Publish publish)
    : device_id_(std::move(device_id)), publish_(std::move(publish)), alarm_(alarm) {}

void Crew::Watch(int64_t stamp_ns, const Pose2& slam, const std::string& floor,
                 const v1::PlanPose& last) {
  crumbs_.Add(slam.position, floor);
  const NoMotionAlarm::Level before = alarm_.level();
  if (!alarm_.Update(stamp_ns, {slam.position.x(), slam.position.y(), slam.z})) return;
  if (alarm_.level() == NoMotionAlarm::Level::kAlert && before != alarm_.level())
    spdlog::warn("ALERT: {} has not moved for {:.0f} s", device_id_, alarm_.still_s());
  publish_(Topic::kAlert, AlertMessage(last));
}

v1::Alert Crew::AlertMessage(const std::optional<v1::PlanPose>& last) const {
  v1::Alert a;
  a.set_kind(ToProto(alarm_.level()));
  a.set_still_s(alarm_.still_s());
  a.set_since_stamp_ns(alarm_.still_since_ns());
  a.set_acknowledged(alarm_.acknowledged());
  a.set_acknowledged_by(alarm_.acknowledged_by());
  if (last) *a.mutable_pose() = *last;
  return a;
}

bool Crew::Acknowledge(const std::string& by, const std::optional<v1::PlanPose>& last) {
  if (!alarm_.Acknowledge(by.substr(0, 64))) return false;
  publish_(Topic::kAlert, AlertMessage(last));
  return true;
}

void Crew::Reset() {
  crumbs_.Clear();
  alarm_.Reset();
}

Route Crew::PlanRoute(const v1::Command::Route& request, const OnPlan& at) const {
  const std::vector<KeepOut> keep_out = markers_.KeepOuts(at.plan_id, at.floor);
  const std::vector<Eigen::Vector2d> back = crumbs_.WayBackOn(at.floor);  // newest first
  const std::optional<Eigen::Vector2d> entry =
      back.empty() ? std::nullopt : std::optional(at.T_plan_slam * back.back());
  Route route;
  switch (request.destination()) {
    case v1::Command::Route::EXIT:
      if (!at.routes->exits().empty()) return at.routes->WayOut(at.wearer, keep_out);
      if (entry) return at.routes->Plan(at.wearer, *entry, keep_out);
      route.error = "the plan marks no exit and no stairs, and the wearer's entry is not known";
      return route;
    case v1::Command::Route::BACKTRACK: {
      if (!entry) {
        route.error = "no way back: no path walked on this floor yet";
        return route;
      }
      std::vector<Eigen::Vector2d> via;
      Eigen::Vector2d last = at.wearer;
      for (const Eigen::Vector2d& slam : back) {
        const Eigen::Vector2d p = at.T_plan_slam * slam;
        if ((p - last).norm() < kBacktrackWaypointM) continue;
        via.push_back(p);
        last = p;
      }
      if (!via.empty() && (via.back() - *entry).norm() < kBacktrackWaypointM) via.pop_back();
      return at.routes->Through(at.wearer, via, *entry, keep_out);
    }
    case v1::Command::Route::POINT:
      return at.routes->Plan(at.wearer, {request.to_x(), request.to_y()}, keep_out);
    default:
      route.error = "unknown route destination " + std::to_string(request.destination());
      return route;
  }
}

std::string Crew::PlaceMarker(const v1::Command::PlaceMarker& request, const OnPlan& at,
                              const Eigen::Vector2d& point, const v1::Reliability& placed_from,
                              v1::Marker* marker) {
  if (request.kind() == v1::Marker::KIND_UNSPECIFIED || !v1::Marker::Kind_IsValid(request.kind()))
    return "marker kind missing or unknown";
  const int64_t now = WallClockNs();
  // Unique across restarts (the clock) and within a millisecond (the count).
  marker->set_id(device_id_ + "-" + std::to_string(now / 1'000'000) + "-" +
                 std::to_string(++placed_));
  marker->set_kind(request.kind());
  marker->set_plan_id(at.plan_id);
  marker->set_floor(at.floor);
  marker->set_x(point.x());
  marker->set_y(point.y());
  marker->set_radius_m(request.radius_m());
  marker->set_text(request.text().substr(0, 1024));
  marker->set_author(device_id_);
  marker->set_created_unix_ns(now);
  marker->set_revision(1);
  *marker->mutable_placed_from() = placed_from;
  std::string why;
  if (markers_.Merge(*marker, &why) == MarkerBoard::Take::kRefused) return why;
  publish_(Topic::kMarker, *marker);
  return {};
}

std::string Crew::OnTeam(Topic topic, const Envelope& e, int64_t now_ns) {
  if (topic != Topic::kMarker) {
    roster_.Take(topic, e, now_ns);
    return {};
  }
  v1::Marker marker;
  if (!marker.ParseFromString(e.payload))
    return "marker from " + e.device_id.substr(0, 64) + " is not a Marker protobuf";
  std::string why;
  switch (markers_.Merge(marker, &why)) {
    case MarkerBoard::Take::kRefused: return "marker refused: " + why;
    case MarkerBoard::Take::kKnown: return {};
    case MarkerBoard::Take::kNew:
    case MarkerBoard::Take::kReplaced: publish_(Topic::kMarker, marker); return {};
  }
  return {};
}

void Crew::PublishMarkers() const {
  for (const auto& [id, m] : markers_.markers()) publish_(Topic::kMarker, m);
}

}  // namespace floorpose::platform
