// Engine (platform/engine.h): the commands for the team, answered by its Crew with the
// plan and alignment in use.
#include "core/frames.h"
#include "platform/engine.h"

namespace floorpose::platform {

std::optional<Crew::OnPlan> Engine::WhereOnPlan(std::string* error) const {
  if (!plans_.current().routes) {
    *error = "no floor plan";
    return std::nullopt;
  }
  const std::optional<v1::PlanPose>& latest = history_.latest();
  if (!latest || latest->alignment_version() == 0 || alignment().version == 0) {
    *error = "no position on the plan yet";
    return std::nullopt;
  }
  return Crew::OnPlan{plans_.current().routes.get(), plans_.current().id, plans_.floor(),
                      alignment().T_plan_slam, Eigen::Vector2d(latest->x(), latest->y())};
}

std::string Engine::PlanRoute(const v1::Command::Route& request, v1::RouteReply* reply) {
  std::string error;
  const std::optional<Crew::OnPlan> at = WhereOnPlan(&error);
  if (!at) return error;
  const int64_t t0 = now_ns_();
  const Route route = crew_.PlanRoute(request, *at);
  if (!route.ok()) return route.error;
  for (const Eigen::Vector2d& p : route.path) {
    v1::PlanPoint* point = reply->add_path();
    point->set_x(p.x());
    point->set_y(p.y());
  }
  reply->set_length_m(route.length_m);
  reply->set_goal_moved_m(route.goal_moved_m);
  *reply->mutable_from_reliability() = history_.latest()->reliability();
  reply->set_time_ms(static_cast<double>(now_ns_() - t0) * 1e-6);
  return {};
}

std::string Engine::PlaceMarker(const v1::Command::PlaceMarker& request, v1::Marker* marker) {
  std::string error;
  const std::optional<Crew::OnPlan> at = WhereOnPlan(&error);
  if (!at) return error + ": the gaze point has no place on the plan";
  const auto& h = request.headset_point();
  const Eigen::Vector3d slam = PointToSlam(frame_, {h.x(), h.y(), h.z()});
  if (!slam.allFinite() || slam.cwiseAbs().maxCoeff() > config().limits().max_abs_coordinate_m())
    return "gaze point not finite or out of range";
  return crew_.PlaceMarker(request, *at, at->T_plan_slam * slam.head<2>(),
                           history_.latest()->reliability(), marker);
}

}  // namespace floorpose::platform
