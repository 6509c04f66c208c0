// The simulator (issue 4): a person wearing a HoloLens walks through a building whose
// floor plan we have; the headset reports poses every 0.3 s in its own drifting SLAM frame
// and a spatial mesh of what its sensors have seen. Ground truth comes along: the true plan
// pose at every headset pose, and ten markers along the walk as in the thesis (section
// 5.1).
//
// What it models, and the figures it was made to match:
// - Reality is not the plan (scenarios): clutter, glass the sensor cannot see, walls on the
//   plan that are not there and walls that are not on the plan (thesis section 7.7), halls.
// - The walk: random goals across the walkable region, joined by A* paths (free_space.h),
//   at 1.0-1.5 m/s with stops; the head looks around while walking and scans the room
//   when stopped. Or a given trajectory on the plan.
// - The sensor: rays in a 70 x 60 degree field of view hit walls, objects, floor and
//   ceiling; hits within 0.8-3.5 m mark surface patches as seen, so the mesh grows only
//   where the head looks.
// - The mesh: 2 m columns (one mesh id each) re-meshed from every patch seen in them, in
//   the SLAM frame of that moment, with 4 cm of noise per patch and 2.5 cm per vertex:
//   ADDED, then UPDATED when more was seen, sometimes REMOVED when far behind.
// - The SLAM drift: odometry scale error, heading bias and random walk, calibrated so that
//   a few hundred metres end about 1% of the distance off and the best SE(2) fit of the
//   whole walk leaves about 0.8 m mean error (Huebner et al. 2020: 2.4 m over 287 m;
//   thesis table 7.2: 0.79 m).
// - The wall pick (initial alignment) is a gaze hit on a wall in the mesh (thesis section
//   6.3.3), so it waits until one is meshed within sensor range; it is off by up to 9
//   degrees and 2.5 m (thesis table 7.1).
//
// Deterministic: the same plan, options and seed give the same output, bit for bit
// (SplitMix64 only, no std distributions, ordered containers only; only the platform's
// libm, through sin/cos/log, could make another machine differ).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/floor_plan.h"
#include "core/se2.h"
#include "core/sim/demo_walk.h"
#include "core/tracking/alignment.h"

namespace floorpose::sim {

enum class Scenario {
  kCorridor,  // reality equals the plan; goals far apart, so the walk follows long hallways
  kOffice,    // desks, cabinets and people in the rooms, none of them on the plan
  kGlass,     // about 30% of the wall length (long walls) is glass: invisible to the sensor
  kHall,      // the walk stays in the plan's most open area; only far walls are in range
  kMismatch,  // ~15% of plan walls absent, extra walls and objects that are not on the plan
  // Reality that differs from the plan as real buildings do. In these the walk is planned
  // on reality's free space, not the plan's.
  kDoors,       // the plan draws every door closed (a line across each opening <= 1.5 m)
  kStale,       // changed since drawn: ~20% of interior walls gone, new walls, ~10% moved
  kScaled,      // scanned from paper: 1-2% scale error per axis, up to 0.5 degrees of skew
  kRelocalize,  // the headset loses tracking 2-4 times for 2-10 s, then its frame jumps
};
std::optional<Scenario> ParseScenario(std::string_view name);
const char* ToString(Scenario scenario);
// Every scenario's name, in the enum's order.
const std::vector<std::string>& ScenarioNames();

struct SimulatorOptions {
  uint64_t seed = 1;
  Scenario scenario = Scenario::kOffice;

  // The walk.
  double target_length_m = 300.0;                   // walk until this far...
  double max_duration_s = 900.0;                    // ...or this long
  double min_speed_mps = 1.0, max_speed_mps = 1.5;  // drawn per leg
  double min_stop_s = 2.0, max_stop_s = 8.0;        // at every goal, scanning the room
  double first_stop_s = 4.0;  // scanning at the start, before walking (and the wall pick)
  double min_goal_distance_m = 5.0;
  double body_radius_m = 0.3;
  double eye_height_m = 1.65;
  double max_turn_rate_rad_s = 2.0;  // of the body, towards the path ahead
  double look_around_rad = 0.35;     // head yaw swing while walking (amplitude)
  double max_scan_rad = 2.6;         // head yaw swing when stopped (amplitude, at most)
  double pose_period_s = 0.3;
  double start_s = 1.0;  // virtual time of the first pose

  // Reality.
  double ceiling_m = 2.6;          // walls go from the floor to the ceiling
  double hall_ceiling_m = 4.0;     // the hall scenario's ceiling
  double glass_share = 0.3;        // of the total wall length, glass scenario
  double absent_share = 0.15;      // of the walls, mismatch scenario
  double max_door_m = 1.5;         // doors: openings up to this wide are drawn closed
  double stale_gone_share = 0.2;   // stale: of the interior wall length, gone...
  double stale_moved_share = 0.1;  // ...and moved by 0.3-1 m across itself
  double min_move_m = 0.3, max_move_m = 1.0;
  double min_scale_error = 0.01, max_scale_error = 0.02;  // scaled: per axis, either sign
  double max_skew_rad = 0.5 * M_PI / 180.0;
  // relocalize: tracking lost 2-4 times (after the wall pick) for 2-10 s each, then the
  // SLAM frame jumps by up to 2 m at the wearer and 20 degrees.
  int min_losses = 2, max_losses = 4;
  double min_loss_s = 2.0, max_loss_s = 10.0;
  double max_jump_m = 2.0, max_jump_rad = 20.0 * M_PI / 180.0;

  // The sensor.
  double min_range_m = 0.8, max_range_m = 3.5;
  double fov_h_rad = 70.0 * M_PI / 180.0, fov_v_rad = 60.0 * M_PI / 180.0;
  int rays_h = 24, rays_v = 12;        // per pose, each jittered within its cell
  double head_pitch_rad = -0.17;       // looking slightly down on average...
  double head_pitch_swing_rad = 0.17;  // ...plus or minus this

  // The mesh.
  bool mesh = true;                 // false: poses and ground truth only (drift studies, fast)
  double chunk_m = 2.0;             // one mesh id per chunk column of chunk_m x chunk_m
  double patch_m = 0.5;             // wall and object faces are seen in patches of at most this
  double floor_cell_m = 0.5;        // floor and ceiling patches
  int max_subdivisions = 3;         // a wall patch is 1..this many quads along each side
  double patch_noise_m = 0.04;      // per patch, along its normal (depth error of a surface)
  double vertex_noise_m = 0.025;    // per vertex and axis
  int poses_per_mesh_tick = 4;      // the mesh is updated every this many poses...
  double update_after_s = 4.0;      // ...and a chunk at most this often
  double remove_rate_per_s = 5e-4;  // chance per second that a far chunk is REMOVED
  double remove_min_distance_m = 8.0;

  // SLAM drift. A per-walk scale error and heading bias (random sign), a heading random
  // walk per metre and per second, a position random walk, and pose jitter that does not
  // accumulate. drift_scale multiplies all of them. Calibrated with 300 m walks over real
  // plans (mlstruct 848 and 1058, Heidelberg; 12 seeds each): 0.8-0.9% of the distance off
  // at the end and 0.8-1.1 m mean error after the best fit, against 0.84% (Huebner et al.
  // 2020) and 0.79 m (thesis table 7.2); small plans give less, walks there stay close.
  double drift_scale = 1.0;
  double scale_error_sigma = 0.01;         // odometry scale error, a fraction
  double heading_bias_rad_per_m = 3.5e-4;  // magnitude, times a uniform 0.5..1.5
  double heading_walk_rad_per_sqrt_m = 6e-3;
  double heading_walk_rad_per_sqrt_s = 6e-4;
  double yaw_scale_error_sigma = 0.005;  // of the head's turning, a fraction
  double position_walk_m_per_sqrt_m = 0.03;
  double jitter_m = 0.01, jitter_rad = 0.002;

  // The wall pick: at the first pose from this time on with a plan wall in the mesh within
  // max_range_m (the wall patch nearest the wearer is picked); off by a uniform angle up to
  // max_pick_error_rad and a uniform offset up to max_pick_offset_m about the wearer
  // (thesis table 7.1). Without a mesh, at this time, on the nearest visible plan wall.
  double pick_time_s = 3.0;
  double max_pick_error_rad = 9.0 * M_PI / 180.0;
  double max_pick_offset_m = 2.5;
  double pick_height_m = 1.3;  // above the floor
  // A kidnapped start (issue 7): when kidnap_m > 0 the pick is exactly this far off at
  // the wearer (in a random direction) and turned by kidnap_rad (either way).
  double kidnap_m = 0.0;
  double kidnap_rad = 0.0;
};

// A pose of a given trajectory on the plan (e.g. a TUM file): heading and pitch of the
// viewing direction.
struct TimedPose {
  double t_s = 0.0;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  double heading = 0.0;
  double pitch = 0.0;
};

// A walk through given waypoints (plan frame, times increasing, at least two), at their
// own timing and straight from one to the next (the person went there, whatever the plan
// says), as head poses every pose period with the simulator's head motion: the body turns
// towards the leg it walks at max_turn_rate_rad_s, the head looks around and pitches, and
// before the first waypoint the wearer stands first_stop_s scanning the room (as a
// generated walk starts, for the wall pick). Times start at 0. Empty on fewer than two
// waypoints.
std::vector<TimedPose> WalkWaypoints(const std::vector<TimedPose>& waypoints,
                                     const SimulatorOptions& options);

struct SimulatedStep {
  int64_t stamp_ns = 0;  // virtual time
  Pose2 true_plan;       // ground truth: plan frame, heading of the view, z above the floor
  Pose2 slam;            // what the headset reports (slam frame, Z up, z above the start)
  // The drifting SLAM frame on the plan now (without the pose jitter): the frame the
  // meshes of this step are in, slam = T_slam_plan * plan.
  Se2 T_slam_plan;
  uint32_t marker = 0;          // 1..10 at the markers, else 0
  std::vector<SimMesh> meshes;  // published just before this pose
  int floor = 0;                // 0, or 1 once up the stairs (ClimbStairs)
};

// What the world holds that the plan does not say: for tests and descriptions.
struct Reality {
  std::vector<uint8_t> plan_wall_present;  // per plan segment
  std::vector<uint8_t> plan_wall_glass;    // per plan segment: present, but invisible
  // Per plan segment: where the wall stands, relative to where the plan draws it (stale).
  std::vector<Eigen::Vector2d> plan_wall_offset;
  // Objects and walls not on the plan, as footprints extruded from the floor.
  struct Prism {
    std::vector<Eigen::Vector2d> footprint;
    double height_m = 0.0;
    std::string kind;  // desk, cabinet, person, wall, pillar, box
  };
  std::vector<Prism> extras;
  double ceiling_m = 0.0;
};

// A loss of tracking (scenario relocalize): no poses and no meshes from lost_s to
// found_s (virtual time of the first pose, and of the first pose after), after which the
// SLAM frame has jumped: slam_after = jump * slam_before for the same true pose.
struct Relocalization {
  double lost_s = 0.0, found_s = 0.0;
  Se2 jump;
  double jump_m = 0.0;  // how far the jump moved the headset's own position
};

struct MeshCounts {
  size_t added = 0, updated = 0, removed = 0, vertices = 0, triangles = 0;
};

struct Simulation {
  std::string error;  // empty on success
  bool ok() const { return error.empty(); }
  std::vector<SimulatedStep> steps;
  // The plan as drawn: what the daemon is given. The input plan, except in doors (the
  // openings closed) and scaled (scaled and skewed by plan_from_reality about the input's
  // centre). Ground truth and the pick's plan side are in this plan's frame.
  FloorPlan plan;
  Eigen::Matrix2d plan_from_reality = Eigen::Matrix2d::Identity();
  std::vector<Relocalization> relocalizations;
  WallPick pick;               // slam / plan frames; AlignFromWallPick(pick) = the start error
  double pick_height_m = 0.0;  // slam z of the picked point
  size_t pick_step = 0;        // the pick is made right after this step's pose
  Se2 pick_error;              // AlignFromWallPick(pick) * truth^-1 at the pick
  Se2 T_slam_plan_initial;     // the true SLAM frame on the plan at the start
  double length_m = 0.0;
  double duration_s = 0.0;
  Reality reality;
  MeshCounts counts;
  std::string description;  // the settings, human-readable
};

// Simulates a walk on `plan`: a generated one, or along `trajectory` (plan frame,
// increasing times) when given.
Simulation Simulate(const FloorPlan& plan, const SimulatorOptions& options,
                    const std::vector<TimedPose>* trajectory = nullptr);

// Two floors of one layout, one above the other: after step `at_step` the wearer stands
// while the headset rises `floor_height_m` over `climb_s` (a flight of stairs, poses every
// period as before, no meshes), then walks the rest of the simulation on the upper
// floor: later poses and meshes floor_height_m higher, meshes under new ids (ADDED when
// first seen up there; removals of chunks never seen there dropped), steps from the top
// of the stairs on at floor 1, later stamps shifted by the climb. Returns an error (a
// step out of range, or at or before the wall pick), else empty.
std::string ClimbStairs(Simulation* simulation, size_t at_step, double floor_height_m,
                        double climb_s);

// The least-squares rigid transform taking `from` onto `to` (Umeyama 1991, in 2D, no
// scale). Identity on fewer than two points.
Se2 FitSe2(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to);

// The SLAM drift of a walk, measured like the thesis (section 7.2, table 7.2) and Huebner
// et al. 2020.
struct DriftStats {
  double length_m = 0.0;
  double end_error_m = 0.0;      // last pose, with the SLAM frame known exactly at the start
  double best_fit_mean_m = 0.0;  // after the best SE(2) fit of all slam to true positions
  double best_fit_max_m = 0.0;
  Se2 best_fit;  // T_plan_slam
};
DriftStats MeasureDrift(const Simulation& simulation);

}  // namespace floorpose::sim
