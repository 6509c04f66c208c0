// What floorposed does for the team beyond its wearer's plan pose: the no-motion alert,
// the way out and the way back, the markers and the teammates (platform/engine.h hands it
// the poses, commands and team topics, and the plan and alignment in use).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/breadcrumbs.h"
#include "core/no_motion.h"
#include "core/route_planner.h"
#include "core/se2.h"
#include "floorpose/v1/floorpose.pb.h"
#include "platform/dds.h"
#include "platform/team.h"

namespace floorpose::platform {

class Crew {
 public:
  using Publish = std::function<void(Topic, const google::protobuf::Message&)>;
  Crew(std::string device_id, const NoMotionOptions& alarm, Publish publish);

  // A pose taken in order: the way back keeps it, the alarm watches it (and publishes the
  // alert when it changes). `last`: the plan pose published for it.
  void Watch(int64_t stamp_ns, const Pose2& slam, const std::string& floor,
             const v1::PlanPose& last);
  v1::Alert AlertMessage(const std::optional<v1::PlanPose>& last) const;
  // False when there is no alert to acknowledge; else published as acknowledged.
  bool Acknowledge(const std::string& by, const std::optional<v1::PlanPose>& last);
  // A new slam frame (Command.reset): the way back and the alarm start again.
  void Reset();

  // The plan and alignment in use, and the wearer on it.
  struct OnPlan {
    const RoutePlanner* routes = nullptr;
    std::string plan_id, floor;
    Se2 T_plan_slam;
    Eigen::Vector2d wearer = Eigen::Vector2d::Zero();
  };
  // Command.route from the wearer, clear of the floor's HAZARD and BLOCKED markers.
  Route PlanRoute(const v1::Command::Route& request, const OnPlan& at) const;
  // Command.place_marker at `point` (plan frame); published. Returns why not, or empty.
  std::string PlaceMarker(const v1::Command::PlaceMarker& request, const OnPlan& at,
                          const Eigen::Vector2d& point, const v1::Reliability& placed_from,
                          v1::Marker* marker);

  // A marker, plan pose or status of any device; a marker new to us is re-published (held
  // for those who join later). Returns why a marker was refused, or empty.
  std::string OnTeam(Topic topic, const Envelope& e, int64_t now_ns);
  void PublishMarkers() const;
  MarkerBoard& markers() { return markers_; }
  std::vector<v1::Teammate> Teammates(int64_t now_ns) const { return roster_.Teammates(now_ns); }

 private:
  std::string device_id_;
  Publish publish_;
  NoMotionAlarm alarm_;  // of the wearer's head, headset time
  Breadcrumbs crumbs_;   // the way back, slam frame
  MarkerBoard markers_;  // the team's markers, every plan
  Roster roster_;        // the team's latest poses and states
  uint64_t placed_ = 0;  // markers placed, for their ids
};

}  // namespace floorpose::platform
