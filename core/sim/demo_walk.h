// A simple simulated walk for the demo and the daemon's integration tests: a wearer
// follows waypoints through a floor plan at walking speed, the headset reports poses
// every 0.3 s in a drifting SLAM frame, and the walls within sensor range come in as
// mesh chunks (ADDED, then UPDATED as more is seen) with vertex noise and a floor.
// The simulator issue replaces this with a realistic one (occlusion, clutter, glass).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/floor_plan.h"
#include "core/se2.h"
#include "core/tracking/alignment.h"

namespace floorpose::sim {

struct DemoWalkOptions {
  uint64_t seed = 1;
  double speed_mps = 1.2;
  double pose_period_s = 0.3;
  int poses_per_mesh_update = 3;
  double sensor_range_m = 3.5;
  double chunk_m = 3.0;  // mesh chunk size (one mesh id a chunk)
  double piece_m = 0.5;  // wall pieces, each a quad from floor to wall_height
  double wall_height_m = 2.5;
  double vertex_noise_m = 0.02;
  double update_after_s = 4.0;  // a chunk seen again this much later is UPDATED
  // SLAM drift: heading bias and odometry scale error, plus the initial offset of the
  // SLAM frame from the plan.
  double heading_drift_rad_per_m = 0.0015;
  double scale_error = 0.01;
  double initial_theta_rad = 0.6;
  Eigen::Vector2d initial_offset_m{3.0, -2.0};
  // Error of the wall pick in the headset, metres and radians.
  double pick_point_error_m = 0.05;
  double pick_normal_error_rad = 0.03;
};

enum class MeshChange { kAdded, kUpdated, kRemoved };

struct SimMesh {
  uint64_t id = 0;
  MeshChange change = MeshChange::kAdded;
  std::vector<Eigen::Vector3f> vertices_slam;  // right-handed, Z up
  std::vector<uint32_t> triangles;
};

struct SimStep {
  int64_t stamp_ns = 0;
  Pose2 true_plan;              // ground truth on the plan
  Pose2 slam;                   // what the headset reports (slam frame)
  std::vector<SimMesh> meshes;  // published just before this pose
};

struct DemoWalk {
  std::vector<SimStep> steps;
  WallPick pick;  // in slam / plan frames
  double pick_height_m = 1.5;
  Se2 T_slam_plan_initial;  // the truth at the start
  double length_m = 0.0;
};

DemoWalk SimulateDemoWalk(const FloorPlan& plan, const std::vector<Eigen::Vector2d>& waypoints,
                          const DemoWalkOptions& options);

}  // namespace floorpose::sim
