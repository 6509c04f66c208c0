// `floorpose simulate` as functions: a simulated walk (core/sim/simulator.h) written as a
// recording of the envelopes the daemon would receive, plus ground truth on topics that
// never exist on DDS (replay skips them). Used by the command line and the tests.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "core/floor_plan.h"
#include "core/frames.h"
#include "core/sim/simulator.h"
#include "floorpose/v1/floorpose.pb.h"

namespace floorpose::tools {

inline constexpr char kSimInfoTopic[] = "floorpose/sim/info";
inline constexpr char kGroundTruthTopic[] = "floorpose/sim/ground_truth";

struct SimulateRecordingOptions {
  std::string device_id = "sim-headset";
  std::string floor = "0";  // floor id of the ground truth
  // Two floors of one layout (sim::ClimbStairs): the walk climbs a flight of stairs this
  // far through its poses (0: one floor), floor_height_m over climb_s, onto upper_floor.
  double stairs_at = 0;
  double floor_height_m = 3.5;
  double climb_s = 10.0;
  std::string upper_floor = "1";
  HeadsetFrame frame = HeadsetFrame::kUnityLeftHandedYUp;
  // What the poses say the device moves on (a CARMEN robot: WHEEL).
  v1::HeadsetPose::Odometry odometry = v1::HeadsetPose::VISUAL_INERTIAL;
};

struct SimulateRecordingResult {
  sim::Simulation simulation;
  sim::DriftStats drift;
  size_t records = 0;
  uint64_t bytes = 0;
};

// Writes a recording: SimulationInfo first, then in time order per pose its mesh deltas,
// the HeadsetPose and its GroundTruthPose, and the wall-pick Command right after the pick
// step's pose. Every stamp (envelope, message and receive stamp) is the virtual time, so
// the file depends on the simulation only. Envelope seq counts per topic from 1.
bool WriteSimulationRecording(const sim::Simulation& simulation, const std::string& plan_id,
                              const std::string& scenario, uint64_t seed,
                              const SimulateRecordingOptions& recording, const std::string& path,
                              size_t* records, std::string* error);

// Simulate, then WriteSimulationRecording; `trajectory` may be null (a generated walk).
bool SimulateToRecording(const FloorPlan& plan, const sim::SimulatorOptions& options,
                         const std::vector<sim::TimedPose>* trajectory,
                         const SimulateRecordingOptions& recording, const std::string& path,
                         SimulateRecordingResult* result, std::string* error);

// Whether the simulation's plan as drawn is not the plan it was given (scenarios doors,
// scaled): the daemon must then be given the drawn one, which WriteDrawnPlan writes as
// GeoJSON in metres.
bool PlanDiffersFromInput(const sim::Simulation& simulation, const FloorPlan& input);
bool WriteDrawnPlan(const sim::Simulation& simulation, const std::string& path, std::string* error);

// A TUM trajectory on the plan: `timestamp x y z qx qy qz qw` per line (seconds, metres;
// '#' starts a comment), times increasing. The viewing direction is the rotated x axis
// (heading and pitch from it); z is not used (the simulator's eye height applies).
bool ParseTumTrajectory(std::string_view text, std::vector<sim::TimedPose>* out,
                        std::string* error);

// The same from a file (at most 256 MB); the error names the file.
bool ReadTumTrajectory(const std::string& path, std::vector<sim::TimedPose>* out,
                       std::string* error);

// Walks given as waypoints: `walk,t_ms,x_m,y_m` per line (walk id, milliseconds, plan
// frame metres), a header line first; a walk's lines in time order, walks in any order.
// A waypoint at the same time as the one before it is dropped (counted in `repeated`).
struct WaypointWalks {
  std::vector<std::string> ids;  // in the order first seen
  std::map<std::string, std::vector<sim::TimedPose>> walks;
  size_t repeated = 0;
};
bool ParseWaypoints(std::string_view text, WaypointWalks* out, std::string* error);
// The same from a file (at most 256 MB); the error names the file.
bool ReadWaypoints(const std::string& path, WaypointWalks* out, std::string* error);
// How a waypoint walk is simulated (eval-suite --waypoints, and simulate --waypoints to
// trace one alone): every walk its own headset, a drift (scale error, heading bias, random
// walks) drawn from its id, so that a floor's walks measure many SLAM runs, not one; on a
// building that is its plan (the corridor scenario), the walk being the person's.
sim::SimulatorOptions WaypointWalkSimulator(const std::string& walk);
// The floor a waypoint CSV walks (its folder's name): the plan's id the suite gives it,
// which keys the simulator's walk.
std::string WaypointFloorName(const std::string& csv_path);

// Re-times a trajectory whose clock is not seconds (a log's line numbers): each step
// takes as long as walking it at pace_mps or turning it at turn_rad_s, whichever is
// longer (at least 10 ms), starting at the first pose's time.
void PaceTrajectory(std::vector<sim::TimedPose>* trajectory, double pace_mps, double turn_rad_s);

}  // namespace floorpose::tools
