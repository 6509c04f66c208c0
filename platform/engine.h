// The daemon's decisions without its threads or DDS: decode and validate inputs, keep the
// wall store, correct poses, schedule and accept registrations, and say what to publish.
// floorposed drives it from its io thread (registrations on a worker); `floorpose eval`
// drives it from a recording on a virtual clock, registrations inline. Same code, so
// the two give the same plan poses.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/explored_map.h"
#include "core/frames.h"
#include "core/global_search.h"
#include "core/registration.h"
#include "core/rooms.h"
#include "core/route_planner.h"
#include "core/tracking/alignment.h"
#include "core/tracking/mcl.h"
#include "core/wall_store.h"
#include "floorpose/v1/config.pb.h"
#include "floorpose/v1/floorpose.pb.h"
#include "platform/codec.h"
#include "platform/config.h"
#include "platform/crew.h"
#include "platform/dds.h"
#include "platform/device_clock.h"
#include "platform/floor_follower.h"
#include "platform/floor_plan_io.h"
#include "platform/intake.h"
#include "platform/jobs.h"
#include "platform/plan_assets.h"
#include "platform/pose_history.h"

namespace floorpose::platform {

// The order inputs are taken in, by the daemon per batch and by `floorpose eval` over a
// recording: by stamp, and at equal stamps meshes, then poses, then commands (a command
// sent with a pose's stamp applies from the next pose on).
inline bool InputBefore(Topic a, int64_t stamp_a, Topic b, int64_t stamp_b) {
  auto rank = [](Topic t) { return t == Topic::kMeshDelta ? 0 : t == Topic::kHeadsetPose ? 1 : 2; };
  return stamp_a != stamp_b ? stamp_a < stamp_b : rank(a) < rank(b);
}

class Engine {
 public:
  // Receives every message to publish, with its topic.
  using Publish = std::function<void(Topic, const google::protobuf::Message&)>;

  // now_ns stamps statuses: the daemon's monotonic clock, or a virtual one.
  Engine(v1::FloorposedConfig configured, Publish publish, std::function<int64_t()> now_ns);

  // Loads the configured plan, if any; returns the error (the engine then waits for a
  // LoadPlan command).
  std::string Start();

  // Runs `work` on another thread, then `done` on the engine's own (the daemon's io
  // thread), so that a plan loaded by command is built without holding up the poses.
  // Unset (floorpose eval, the tests): both at once, in order.
  using Offload = std::function<void(std::function<void()> work, std::function<void()> done)>;
  void SetOffload(Offload offload) { offload_ = std::move(offload); }

  // Inputs. Envelopes of other devices are ignored (another daemon serves them).
  void OnMeshDelta(const Envelope& e);
  void OnHeadsetPose(const Envelope& e);
  void OnCommand(const Envelope& e);
  // What the rest of the team publishes, of every device: markers (kept, re-published
  // when new, so that they outlive their author's writer), plan poses and statuses (the
  // teammates).
  void OnTeam(Topic topic, const Envelope& e) {
    if (std::string why = crew_.OnTeam(topic, e, now_ns_()); !why.empty())
      intake_.Warn("marker", why);
  }
  // Samples of `topic` DDS lost or rejected before they reached us: counted and logged.
  void OnDdsLosses(Topic topic, uint64_t lost, uint64_t rejected) {
    intake_.OnDdsLosses(topic, lost, rejected);
  }

  // The worker's job when one is due and none is running, and its result.
  std::optional<Job> TakeDueJob();
  void OnRegistrationDone(Done done);
  bool registration_running() const { return jobs_.running(); }

  // Publishes a status (message: a command's result, or empty).
  void PublishStatus(const std::string& message);
  v1::DaemonStatus Status(const std::string& message) const;
  std::string StatusLine() const;

  // Crash safety (state_dir): what to save, and resuming from it. RestoreState refuses,
  // with the reason, a snapshot of another device, of a plan that is gone or changed, or
  // with values out of range; on refusal nothing of it is kept.
  v1::StateSnapshot SaveState() const;
  std::string RestoreState(const v1::StateSnapshot& snapshot);
  // Publishes the alignment in use (version 0: none), as after every change.
  void PublishAlignment();

  const v1::DaemonStatus::Counters& counters() const { return intake_.counters(); }
  // The estimator: its alignment, state and reliability.
  const tracking::MclTracker& tracker() const { return tracker_; }
  const AlignmentState& alignment() const { return tracker_.alignment(); }
  TrackState state() const { return tracker_.state(); }
  Reliability reliability() const { return tracker_.CurrentReliability(); }
  const WallStore& store() const { return store_; }
  // The configuration in use: as configured, for the device's odometry (ForOdometry).
  const v1::FloorposedConfig& config() const { return config_.get(); }
  // What the wearer has explored on the loaded plan; null without a plan or when disabled.
  const ExploredMap* explored() const { return plans_.current().explored.get(); }
  // Publishes the explored map now if it changed since the last one.
  void PublishExplored();
  // The alert, the way back, the markers and the teammates. The daemon saves and restores
  // the markers (markers.pb) and publishes them all at start, for those who join later.
  Crew& crew() { return crew_; }

 private:
  // A plan file, or floor `floor` of a .floors set.
  std::string LoadPlan(const std::string& path, const std::string& floor);
  // A plan read and built (ReadPlan, on any thread) becomes the plan in use, or its
  // refusal is counted.
  std::string UseLoad(PlanLoad load);
  // Command.load_plan: starts reading and building the plan (on offload_ when there is
  // one), answered when it is built; why not, if it cannot start.
  std::string StartLoadPlan(const v1::Command& cmd, const v1::CommandReply& reply);
  // A mesh delta's parts: REMOVED; a late copy of an older scan than the store's (true:
  // dropped); the extraction's limits and dropped triangles (false: refused); the walls
  // into the store, making room at limits.max_wall_points.
  void RemoveMesh(uint64_t mesh_id);
  bool OlderThanStored(const DecodedMesh& mesh);
  bool Extracted(const DecodedMesh& mesh, const WallExtractionReport& report);
  void StoreWalls(const DecodedMesh& mesh, std::vector<WallPoint> points,
                  const WallExtractionReport& report);
  // The end of a command: its reply and status, and what it changed published.
  void FinishCommand(const v1::Command& cmd, v1::CommandReply reply, const std::string& error,
                     const std::string& done);
  // The plan in use (plans_) is new: the alignment goes with the old plan, or stays when
  // the new one is another floor of the same set.
  void UsePlan(bool another_floor);
  // A .floors set: takes the floor the headset's height says, once it has said so for
  // floors.change_hold_s.
  void FollowFloors(const DecodedPose& pose);
  // The recent trajectory under the alignment in use (PlanTrack).
  void PublishTrack();
  v1::PlanPose ToPlanPose(const PlanPoseEstimate& est, int64_t stamp_ns) const;
  // Maps an input's stamp onto the device's timeline, in place; false: refused.
  bool TakeStamp(const std::string& what, int64_t* stamp_ns);
  // The wall options with the height band about the wearer's eyes, once a pose is known.
  WallExtractionOptions BandedWallOptions() const;
  bool Mine(const Envelope& e) const { return e.device_id == config().dds().device_id(); }
  // The device moves on a new odometry (config_ has taken it): tracked with its drift.
  void UseOdometry(v1::HeadsetPose::Odometry odometry);
  // The plan and alignment in use and the wearer's latest plan position, for the crew's
  // routes and markers; why there are none (no plan, no position yet) in *error.
  std::optional<Crew::OnPlan> WhereOnPlan(std::string* error) const;
  // Command.route and Command.place_marker: the reply's part, or why not.
  std::string PlanRoute(const v1::Command::Route& request, v1::RouteReply* reply);
  std::string PlaceMarker(const v1::Command::PlaceMarker& request, v1::Marker* marker);
  // The walls of a mesh just stored, traced from the wearer into the explored map while
  // the position is RELIABLE.
  void ExploreWalls(const std::vector<WallPoint>& points);

  DeviceConfig config_;  // as configured, for the device's odometry
  Publish publish_;
  std::function<int64_t()> now_ns_;
  HeadsetFrame frame_;
  WallExtractionOptions wall_options_;
  tracking::MclTracker tracker_;
  WallStore store_;
  PlansInUse plans_;  // the plan in use (its index is the tracker's), and a set's other floors
  Offload offload_;
  bool plan_loading_ = false;  // a load_plan command is being built elsewhere
  Intake intake_;              // the device's timeline, its refusals counted, warnings paced
  PoseHistory history_;        // the latest pose as published, the eye height, the recent track
  Crew crew_;                  // the alert, the way back, markers, teammates
  JobScheduler jobs_;          // the worker's: which is due, the latest update's result
};

}  // namespace floorpose::platform
