// The team lead's dashboard (`floorpose dashboard`): every device's plan poses, alignment
// and status from DDS, kept per device, and served to browsers as JSON and a server-sent
// event stream. DashboardState is the model (thread-safe: one DDS thread writes, any number
// of HTTP threads read); Dashboard joins DDS and serves HTTP.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "core/floor_plan.h"
#include "core/rooms.h"
#include "floorpose/v1/floorpose.pb.h"
#include "platform/dds.h"
#include "platform/team.h"
#include "tools/lib/cot.h"

namespace floorpose::tools {

struct DashboardOptions {
  double stale_after_s = 5.0;   // a device without a plan pose this long is shown greyed
  size_t trail_points = 600;    // per device; the oldest go first
  double frame_period_s = 0.1;  // pushes to a browser are coalesced to at most this rate
  std::map<std::string, std::string> names;  // device id -> name shown; default: the id
  size_t max_devices = 256;  // more device ids than a team has: the rest are ignored, logged
  // A plan pose stamped this much before the one shown is a headset whose clock started
  // again (its app restarted; floorposed's limits.restart_gap_s): it is shown, and its
  // trail starts again.
  double restart_gap_s = 5.0;
};

class DashboardState {
 public:
  using Clock = std::chrono::steady_clock;
  explicit DashboardState(DashboardOptions options) : options_(std::move(options)) {}

  void OnPlanPose(const std::string& device, const v1::PlanPose& pose, Clock::time_point now);
  void OnPlanTrack(const std::string& device, const v1::PlanTrack& track, Clock::time_point now);
  void OnAlignment(const std::string& device, const v1::Alignment& alignment,
                   Clock::time_point now);
  void OnStatus(const std::string& device, const v1::DaemonStatus& status, Clock::time_point now);
  void OnAlert(const std::string& device, const v1::Alert& alert, Clock::time_point now);
  // A marker heard or placed here: true when it is new or newer than the one shown (the
  // caller then publishes it, so that it outlives its author); *why when refused.
  bool OnMarker(const v1::Marker& marker, std::string* why);
  // The marker of that id, if any.
  std::optional<v1::Marker> MarkerById(const std::string& id) const;
  // Where the SEARCHED markers of a plan are (not removed), plan metres.
  std::vector<Eigen::Vector2d> SearchedOn(const std::string& plan_id) const;
  // Saves the markers to `path` when they changed since the last save.
  void SaveMarkers(const std::string& path);
  // A device's explored map; false (and kept out) when its cells do not unpack.
  bool OnExplored(const std::string& device, const v1::ExploredMap& map, Clock::time_point now,
                  std::string* error);

  // The team's explored map of a plan: the latest grid of every device on it summed (the
  // log-odds of independent observers add up), as an RGBA PNG, north up: free cells a
  // light tint, seen walls a darker one, unknown transparent. Empty when none was sent.
  std::string ExploredPng(const std::string& plan_id) const;

  // What one browser has been sent so far.
  struct Cursor {
    uint64_t version = 0;
    std::map<std::string, std::pair<uint64_t, uint64_t>> trails;  // device -> (epoch, next seq)
    uint64_t explored_version = 0;
    uint64_t markers_revision = 0;
  };
  // JSON of the devices changed since *cursor (all of them for a fresh cursor), with every
  // device's age and the stale ones; advances *cursor. Format in docs/dashboard.md.
  std::string Frame(Cursor* cursor, Clock::time_point now) const;
  // Blocks until something changed after `version`, the timeout passes or Stop().
  void WaitForChange(uint64_t version, std::chrono::milliseconds timeout) const;
  void Stop();
  bool stopped() const { return stopped_; }
  size_t devices() const;

 private:
  struct TrailPoint {
    double x, y;
    int flag;
    int64_t stamp_ns;
  };
  struct Device {
    std::optional<v1::PlanPose> pose;
    std::optional<v1::DaemonStatus> status;
    std::optional<v1::Alignment> alignment;
    std::optional<v1::Alert> alert;           // the latest, from the alert topic or a status
    std::optional<v1::ExploredMap> explored;  // without its packed cells
    std::vector<int8_t> explored_cells;
    std::deque<TrailPoint> trail;
    uint64_t trail_epoch = 1;      // bumped when the trail is replaced (a new PlanTrack)
    uint64_t trail_first_seq = 0;  // seq of trail.front()
    // Staleness counts from the last plan pose (a daemon still reports status when the
    // headset went quiet), or from the last message of a device that never had a pose.
    Clock::time_point last_pose, last_message;
    uint64_t version = 0;
  };
  // The device's entry, now updated; null when it would be one too many. Under mu_.
  Device* Touch(const std::string& device, Clock::time_point now);
  void Append(Device& d, const v1::PlanPose& p);
  // The devices' grids of a plan that share the first one's geometry (by device id).
  std::vector<const Device*> ExploredOf(const std::string& plan_id) const;  // under mu_
  // Parts of a Frame, under mu_: a device's name, state, pose, alert and alignment; the
  // trail points *cursor lacks (advancing it); every plan's explored grid; every marker.
  nlohmann::json DeviceJson(const std::string& id, const Device& d) const;
  nlohmann::json TrailJson(const std::string& id, const Device& d, Cursor* cursor) const;
  nlohmann::json ExploredJson() const;
  nlohmann::json MarkersJson() const;

  DashboardOptions options_;
  mutable std::mutex mu_;
  mutable std::condition_variable changed_;
  std::map<std::string, Device> devices_;
  uint64_t version_ = 0;
  uint64_t explored_version_ = 0;
  mutable std::map<std::string, std::pair<uint64_t, std::string>>
      png_cache_;  // plan -> (version, png)
  size_t refused_devices_ = 0;
  platform::MarkerBoard markers_;
  uint64_t saved_markers_ = 0;
  std::atomic<bool> stopped_{false};
};

// A plan the dashboard draws: a plan file, or one floor of a .floors set.
struct DashboardPlan {
  FloorPlan plan;
  std::string set;      // the .floors set's name (its file name without extension), or empty
  std::string floor;    // the floor's id in its set, or empty
  double height_m = 0;  // of that floor, above the set's zero
  std::optional<Georeference> georeference;  // where it lies on the Earth, when it says
};
// The plans of `plan` (a plan file or a .floors set: every floor) and of every plan of
// `plans_dir`, as the daemon's plan_dir. A file that does not load is logged; false when
// it was `plan` (the one asked for) or `plans_dir` has none. The floors of a set share the
// georeference of the first floor that has one.
bool LoadDashboardPlans(const std::string& plan, const std::string& plans_dir,
                        std::vector<DashboardPlan>* plans);
// The georeferenced ones, for Cursor-on-Target.
std::vector<CotPlan> CotPlansOf(const std::vector<DashboardPlan>& plans);
// An RGBA image (rows from the bottom up, as plan grids run) as PNG, north up; empty when
// libpng fails.
std::string EncodePngBottomUp(uint32_t width, uint32_t height,
                              const std::vector<unsigned char>& rgba);

// The plans a dashboard draws, as JSON (docs/dashboard.md, GET /api/plans).
// With `rooms`, each plan's room grid (where GET /api/searched/PLAN.png lies).
std::string PlansJson(const std::vector<DashboardPlan>& plans,
                      const std::map<std::string, std::unique_ptr<RoomMap>>& rooms = {});

struct DashboardServerOptions {
  uint32_t domain_id = 0;
  std::string cyclone_config;  // empty: CYCLONEDDS_URI
  std::string host = "0.0.0.0";
  int port = 8080;                                // 0: any free port
  std::optional<platform::DdsSecurity> security;  // join a secured domain with this identity
  DashboardOptions dashboard;
  std::string markers_path;       // where markers are kept across restarts; empty: not kept
  std::string name = "lead";      // who places markers and acknowledges alerts here
  std::optional<CotOptions> cot;  // also send every wearer and marker as Cursor-on-Target
};

class Dashboard {
 public:
  // Joins DDS and binds the port; throws std::runtime_error when either fails.
  Dashboard(DashboardServerOptions options, std::vector<DashboardPlan> plans);
  ~Dashboard();
  Dashboard(const Dashboard&) = delete;
  Dashboard& operator=(const Dashboard&) = delete;
  int port() const { return port_; }
  const DashboardState& state() const { return *state_; }
  // Serves until Stop() (from any thread).
  void Serve();
  void Stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::unique_ptr<DashboardState> state_;
  int port_ = 0;
};

// The port of a `floorpose dashboard` started with --port 0, from its log line
// "dashboard on http://HOST:PORT/"; 0 when it did not appear within the timeout.
int DashboardPortFromLog(const std::string& log_path, std::chrono::milliseconds timeout);

}  // namespace floorpose::tools
