// `floorpose import-carmen` as functions: a CARMEN laser log (a wheeled robot's 2D laser
// scans) becomes a recording the daemon can be evaluated on, as if a headset had sent it.
//
// - Each scan is a vertical wall mesh: consecutive beam end points joined into quads from
//   the floor to wall_height_m, broken where the range jumps, max-range readings dropped.
// - The meshes and the poses (every pose_period_s) are in the frame of the drifting wheel
//   odometry (ODOM.tum): that is the "SLAM" the daemon has to correct.
// - Ground truth is the corrected pose of each scan (GT.tum, one line per FLASER message in
//   log order); between scans the odometry's own motion carries it, blended from the scans
//   on either side so it meets both.
// - The initial alignment is exact (the first ground-truth pose), sent as a wall pick.
// - Logs whose timestamps are unusable carry the message's line number instead (the data
//   set's README says which); that is detected (every GT time is its scan's line number),
//   and the walk is then paced at pace_mps along the ground truth (turning in place at
//   turn_rad_s), the odometry mapped onto that clock between scans.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/frames.h"
#include "core/sim/simulator.h"

namespace floorpose::tools {

struct CarmenScan {
  size_t line = 0;         // 0-based line number in the (decompressed) log
  double timestamp = 0.0;  // the message's ipc_timestamp (may be garbage in some logs)
  std::vector<float> ranges;
  Pose2 corrected;  // the pose logged with the scan (GMapping-corrected in these logs)
};

struct CarmenLog {
  std::vector<CarmenScan> scans;
  size_t lines = 0;
  size_t skipped_lines = 0;  // other messages (ODOM, PARAM, NEFF, ...)
  float max_reading = 0.0f;  // the largest range in the log: the scanner's "no return"
};

// FLASER messages only (`FLASER n r_1..r_n x y theta odom_x odom_y odom_theta ts host ts`).
// A malformed FLASER line fails with its line number.
bool ParseCarmenLog(std::string_view text, CarmenLog* log, std::string* error);
// The same from a file, gzip-compressed or not.
bool ReadCarmenLog(const std::string& path, CarmenLog* log, std::string* error);

struct CarmenImportOptions {
  double pose_period_s = 0.3;
  double wall_height_m = 2.5;  // the quads go from the floor to this
  double eye_height_m = 1.65;  // the "headset" height above the floor in the poses
  // Readings at or above this are "no return" and dropped; 0: the log's largest reading.
  double max_range_m = 0.0;
  double min_range_m = 0.05;
  // Consecutive end points are joined when closer than break_m plus break_beams beam
  // spacings at the nearer range (a wall seen at a grazing angle stays one wall).
  double break_m = 0.3;
  double break_beams = 5.0;
  double pace_mps = 0.5;          // line-number logs: walking speed...
  double turn_rad_s = M_PI / 4;   // ...and turning in place
  double pick_max_range_m = 8.0;  // the wall pick is on a scan point this near
  // Where the odometry says nothing for longer than this (a log with a clock in seconds),
  // the robot's motion is unknown, as a headset's is while it has lost tracking: no pose
  // and no scan is sent then, and the daemon reads the silence as a loss of tracking
  // (tracking.motion.lost_after_s). Interpolating across it would report a robot that
  // stands still while it turns. Seconds.
  double max_odometry_gap_s = 1.5;
  std::string name = "carmen";  // scenario name in the recording
};

struct CarmenImportReport {
  size_t scans = 0, readings = 0, dropped_readings = 0, triangles = 0;
  bool line_clock = false;  // timestamps were line numbers: paced walk
  double length_m = 0, duration_s = 0;
  double odom_final_error_m = 0, odom_max_error_m = 0;  // odometry alone, from the exact start
  size_t odometry_gaps = 0;  // silences over max_odometry_gap_s within the walk...
  double silent_s = 0;       // ...their time, with no pose and no scan
  size_t silent_scans = 0;
};

// Builds the walk as a Simulation (steps, meshes, ground truth, the exact wall pick), so
// that WriteSimulationRecording writes it like any simulated walk.
bool CarmenToSimulation(const CarmenLog& log, const std::vector<sim::TimedPose>& odometry,
                        const std::vector<sim::TimedPose>& ground_truth,
                        const CarmenImportOptions& options, sim::Simulation* out,
                        CarmenImportReport* report, std::string* error);

}  // namespace floorpose::tools
