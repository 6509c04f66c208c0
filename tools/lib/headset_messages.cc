#include "tools/lib/headset_messages.h"

#include <Eigen/Geometry>
#include <cmath>

namespace floorpose::tools {
namespace {

// The headset<->slam conversions are their own inverses (a swap of y and z), so the same
// functions take slam back to the headset convention.
Eigen::Vector3d ToHeadset(HeadsetFrame frame, const Eigen::Vector3d& p) {
  return PointToSlam(frame, p);
}

}  // namespace

v1::MeshDelta ToMeshDelta(const sim::SimMesh& mesh, HeadsetFrame frame, int64_t stamp_ns) {
  v1::MeshDelta m;
  m.set_mesh_id(mesh.id);
  m.set_stamp_ns(stamp_ns);
  switch (mesh.change) {
    case sim::MeshChange::kAdded: m.set_change(v1::MeshDelta::ADDED); break;
    case sim::MeshChange::kUpdated: m.set_change(v1::MeshDelta::UPDATED); break;
    case sim::MeshChange::kRemoved: m.set_change(v1::MeshDelta::REMOVED); return m;
  }
  m.mutable_vertices()->Reserve(static_cast<int>(mesh.vertices_slam.size() * 3));
  for (const Eigen::Vector3f& v : mesh.vertices_slam) {
    const Eigen::Vector3d h = ToHeadset(frame, v.cast<double>());
    m.add_vertices(static_cast<float>(h.x()));
    m.add_vertices(static_cast<float>(h.y()));
    m.add_vertices(static_cast<float>(h.z()));
  }
  m.mutable_triangles()->Add(mesh.triangles.begin(), mesh.triangles.end());
  return m;
}

v1::HeadsetPose ToHeadsetPose(const Pose2& pose, HeadsetFrame frame, int64_t stamp_ns) {
  v1::HeadsetPose out;
  out.set_stamp_ns(stamp_ns);
  out.set_tracking(v1::HeadsetPose::TRACKING_OK);
  const Eigen::Vector3d p = ToHeadset(frame, {pose.position.x(), pose.position.y(), pose.z});
  out.mutable_position()->set_x(p.x());
  out.mutable_position()->set_y(p.y());
  out.mutable_position()->set_z(p.z());
  // The device looks along slam +y (Unity +z) or +x (Z-up): yaw so that it faces heading.
  const double yaw =
      frame == HeadsetFrame::kUnityLeftHandedYUp ? pose.heading - M_PI / 2 : pose.heading;
  const Eigen::Quaterniond q_slam(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  const Eigen::Quaterniond q = OrientationToSlam(frame, q_slam);
  out.mutable_orientation()->set_x(q.x());
  out.mutable_orientation()->set_y(q.y());
  out.mutable_orientation()->set_z(q.z());
  out.mutable_orientation()->set_w(q.w());
  return out;
}

v1::Command ToWallPickCommand(const WallPick& wall_pick, double height_m, HeadsetFrame frame,
                              uint64_t request_id) {
  v1::Command cmd;
  cmd.set_request_id(request_id);
  auto* pick = cmd.mutable_wall_pick();
  const Eigen::Vector3d p =
      ToHeadset(frame, {wall_pick.slam_point.x(), wall_pick.slam_point.y(), height_m});
  const Eigen::Vector3d n =
      ToHeadset(frame, {wall_pick.slam_normal.x(), wall_pick.slam_normal.y(), 0.0});
  pick->mutable_headset_point()->set_x(p.x());
  pick->mutable_headset_point()->set_y(p.y());
  pick->mutable_headset_point()->set_z(p.z());
  pick->mutable_headset_normal()->set_x(n.x());
  pick->mutable_headset_normal()->set_y(n.y());
  pick->mutable_headset_normal()->set_z(n.z());
  pick->set_plan_x(wall_pick.plan_point.x());
  pick->set_plan_y(wall_pick.plan_point.y());
  pick->set_plan_normal_x(wall_pick.plan_normal.x());
  pick->set_plan_normal_y(wall_pick.plan_normal.y());
  return cmd;
}

v1::Command ToWallPickCommand(const sim::DemoWalk& walk, HeadsetFrame frame, uint64_t request_id) {
  return ToWallPickCommand(walk.pick, walk.pick_height_m, frame, request_id);
}

}  // namespace floorpose::tools
