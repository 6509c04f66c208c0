#include "tools/lib/simulate_recording.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "core/random.h"
#include "platform/floor_plan_io.h"
#include "platform/recording.h"
#include "tools/lib/headset_messages.h"
#include "tools/lib/plan_import.h"

namespace floorpose::tools {
namespace {

// Appends envelopes, one seq counter per topic.
class SimRecorder {
 public:
  SimRecorder(const std::string& path, std::string device_id)
      : writer_(path), device_id_(std::move(device_id)) {}
  bool ok() const { return writer_.ok(); }
  const std::string& error() const { return writer_.error(); }
  size_t records() const { return records_; }

  bool Append(const std::string& topic, int64_t stamp_ns, const google::protobuf::Message& msg) {
    v1::RecordingRecord r;
    r.set_receive_stamp_ns(stamp_ns);
    r.set_topic(topic);
    v1::Envelope* e = r.mutable_envelope();
    e->set_device_id(device_id_);
    e->set_seq(++seq_[topic]);
    e->set_stamp_ns(stamp_ns);
    if (!msg.SerializeToString(e->mutable_payload())) return false;
    ++records_;
    return writer_.Append(r);
  }
  bool Flush() { return writer_.Flush(); }

 private:
  platform::RecordingWriter writer_;
  std::string device_id_;
  std::map<std::string, uint64_t> seq_;
  size_t records_ = 0;
};

}  // namespace

bool WriteSimulationRecording(const sim::Simulation& simulation, const std::string& plan_id,
                              const std::string& scenario, uint64_t seed,
                              const SimulateRecordingOptions& recording, const std::string& path,
                              size_t* records, std::string* error) {
  if (!simulation.ok() || simulation.steps.empty()) {
    *error = "nothing to write: " + simulation.error;
    return false;
  }
  SimRecorder out(path, recording.device_id);
  if (!out.ok()) {
    *error = out.error();
    return false;
  }
  const std::string mesh_topic = platform::TopicName(platform::Topic::kMeshDelta);
  const std::string pose_topic = platform::TopicName(platform::Topic::kHeadsetPose);
  const std::string command_topic = platform::TopicName(platform::Topic::kCommand);

  v1::SimulationInfo info;
  info.set_plan_id(plan_id);
  info.set_scenario(scenario);
  info.set_seed(seed);
  info.mutable_t_slam_plan_initial()->set_theta(simulation.T_slam_plan_initial.theta);
  info.mutable_t_slam_plan_initial()->set_x(simulation.T_slam_plan_initial.t.x());
  info.mutable_t_slam_plan_initial()->set_y(simulation.T_slam_plan_initial.t.y());
  info.set_length_m(simulation.length_m);
  info.set_duration_s(simulation.duration_s);
  info.set_device_id(recording.device_id);
  info.set_floor(recording.floor);
  info.set_description(simulation.description);
  bool ok = out.Append(kSimInfoTopic, simulation.steps.front().stamp_ns, info);

  for (size_t i = 0; i < simulation.steps.size() && ok; ++i) {
    const sim::SimulatedStep& step = simulation.steps[i];
    for (const sim::SimMesh& mesh : step.meshes)
      ok = ok &&
           out.Append(mesh_topic, step.stamp_ns, ToMeshDelta(mesh, recording.frame, step.stamp_ns));
    v1::HeadsetPose pose = ToHeadsetPose(step.slam, recording.frame, step.stamp_ns);
    pose.set_odometry(recording.odometry);
    ok = ok && out.Append(pose_topic, step.stamp_ns, pose);
    v1::GroundTruthPose truth;
    truth.set_stamp_ns(step.stamp_ns);
    truth.set_x(step.true_plan.position.x());
    truth.set_y(step.true_plan.position.y());
    truth.set_heading(step.true_plan.heading);
    truth.set_floor(step.floor == 0 ? recording.floor : recording.upper_floor);
    truth.set_marker(step.marker);
    ok = ok && out.Append(kGroundTruthTopic, step.stamp_ns, truth);
    if (i == simulation.pick_step)
      ok = ok && out.Append(command_topic, step.stamp_ns,
                            ToWallPickCommand(simulation.pick, simulation.pick_height_m,
                                              recording.frame, 1));
  }
  ok = ok && out.Flush();
  if (!ok) {
    *error = path + ": write failed" + (out.error().empty() ? "" : ": " + out.error());
    return false;
  }
  if (records) *records = out.records();
  return true;
}

bool SimulateToRecording(const FloorPlan& plan, const sim::SimulatorOptions& options,
                         const std::vector<sim::TimedPose>* trajectory,
                         const SimulateRecordingOptions& recording, const std::string& path,
                         SimulateRecordingResult* result, std::string* error) {
  result->simulation = sim::Simulate(plan, options, trajectory);
  if (!result->simulation.ok()) {
    *error = plan.id + ": " + result->simulation.error;
    return false;
  }
  result->drift = sim::MeasureDrift(result->simulation);
  if (recording.stairs_at > 0) {
    const size_t at = static_cast<size_t>(recording.stairs_at *
                                          static_cast<double>(result->simulation.steps.size()));
    if (const std::string e =
            sim::ClimbStairs(&result->simulation, at, recording.floor_height_m, recording.climb_s);
        !e.empty()) {
      *error = plan.id + ": " + e;
      return false;
    }
  }
  if (!WriteSimulationRecording(result->simulation, plan.id, sim::ToString(options.scenario),
                                options.seed, recording, path, &result->records, error))
    return false;
  std::error_code ec;
  result->bytes = std::filesystem::file_size(path, ec);
  return true;
}

bool PlanDiffersFromInput(const sim::Simulation& simulation, const FloorPlan& input) {
  return simulation.plan.segments.size() != input.segments.size() ||
         !simulation.plan_from_reality.isIdentity();
}

bool WriteDrawnPlan(const sim::Simulation& simulation, const std::string& path,
                    std::string* error) {
  std::ofstream out(path);
  out << platform::ToGeoJson(simulation.plan, "floorpose simulate: the plan as drawn");
  out.close();
  if (!out) {
    *error = path + ": write failed";
    return false;
  }
  return true;
}

bool ParseTumTrajectory(std::string_view text, std::vector<sim::TimedPose>* out,
                        std::string* error) {
  std::istringstream in{std::string(text)};
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    double v[8];
    int got = 0;
    while (got < 8 && (ls >> v[got])) ++got;
    if (got == 0) continue;
    bool finite = true;
    for (int i = 0; i < got; ++i) finite = finite && std::isfinite(v[i]);
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (got != 8 || !finite || q.norm() < 1e-6) {
      *error = "line " + std::to_string(n) + ": expected 'timestamp x y z qx qy qz qw'";
      return false;
    }
    if (!out->empty() && !(v[0] > out->back().t_s)) {
      *error = "line " + std::to_string(n) + ": timestamps must increase";
      return false;
    }
    const Eigen::Vector3d forward = q.normalized() * Eigen::Vector3d::UnitX();
    sim::TimedPose pose;
    pose.t_s = v[0];
    pose.position = {v[1], v[2]};
    pose.heading = std::atan2(forward.y(), forward.x());
    pose.pitch = std::asin(std::clamp(forward.z(), -1.0, 1.0));
    out->push_back(pose);
  }
  if (out->size() < 2) {
    *error = "a trajectory needs at least two poses";
    return false;
  }
  return true;
}

bool ReadTumTrajectory(const std::string& path, std::vector<sim::TimedPose>* out,
                       std::string* error) {
  std::string text;
  if (!platform::ReadFile(path, 256 << 20, &text, error)) return false;
  if (ParseTumTrajectory(text, out, error)) return true;
  *error = path + ": " + *error;
  return false;
}

bool ParseWaypoints(std::string_view text, WaypointWalks* out, std::string* error) {
  std::istringstream in{std::string(text)};
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || (n == 1 && line.rfind("walk,", 0) == 0)) continue;
    std::istringstream fields(line);
    std::string id, t, x, y, rest;
    char* end[3] = {nullptr, nullptr, nullptr};
    double v[3] = {0, 0, 0};
    const bool split = std::getline(fields, id, ',') && std::getline(fields, t, ',') &&
                       std::getline(fields, x, ',') && std::getline(fields, y, ',') &&
                       !std::getline(fields, rest, ',');
    if (split) {
      v[0] = std::strtod(t.c_str(), &end[0]);
      v[1] = std::strtod(x.c_str(), &end[1]);
      v[2] = std::strtod(y.c_str(), &end[2]);
    }
    bool ok = split && !id.empty();
    for (int i = 0; ok && i < 3; ++i) ok = end[i] && *end[i] == '\0' && std::isfinite(v[i]);
    if (!ok) {
      *error = "line " + std::to_string(n) + ": expected 'walk,t_ms,x_m,y_m'";
      return false;
    }
    auto [it, fresh] = out->walks.try_emplace(id);
    if (fresh) out->ids.push_back(id);
    std::vector<sim::TimedPose>& walk = it->second;
    sim::TimedPose p;
    p.t_s = v[0] * 1e-3;
    p.position = {v[1], v[2]};
    if (!walk.empty() && p.t_s < walk.back().t_s) {
      *error = "line " + std::to_string(n) + ": walk " + id + " goes back in time";
      return false;
    }
    if (!walk.empty() && p.t_s == walk.back().t_s) {
      ++out->repeated;
      continue;
    }
    walk.push_back(p);
  }
  if (out->walks.empty()) {
    *error = "no waypoints";
    return false;
  }
  return true;
}

bool ReadWaypoints(const std::string& path, WaypointWalks* out, std::string* error) {
  std::string text;
  if (!platform::ReadFile(path, 256 << 20, &text, error)) return false;
  if (ParseWaypoints(text, out, error)) return true;
  *error = path + ": " + *error;
  return false;
}

sim::SimulatorOptions WaypointWalkSimulator(const std::string& walk) {
  sim::SimulatorOptions options;
  options.seed = Fnv1a(walk);
  options.scenario = sim::Scenario::kCorridor;
  return options;
}

std::string WaypointFloorName(const std::string& csv_path) {
  return std::filesystem::absolute(csv_path).parent_path().filename().string();
}

void PaceTrajectory(std::vector<sim::TimedPose>* trajectory, double pace_mps, double turn_rad_s) {
  for (size_t i = 1; i < trajectory->size(); ++i) {
    const sim::TimedPose& a = (*trajectory)[i - 1];
    sim::TimedPose& b = (*trajectory)[i];
    const double walk = (b.position - a.position).norm() / pace_mps;
    const double turn = std::abs(WrapAngle(b.heading - a.heading)) / turn_rad_s;
    b.t_s = a.t_s + std::max({walk, turn, 0.01});
  }
}

}  // namespace floorpose::tools
