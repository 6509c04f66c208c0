// floorposed: the composition root. An io thread owns the DDS readers, the wall store and
// the tracker; a worker thread runs registrations on snapshots; the caller's (main)
// thread handles signals and systemd.
#pragma once

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/frames.h"
#include "core/registration.h"
#include "core/tracker.h"
#include "core/wall_store.h"
#include "floorpose/v1/config.pb.h"
#include "floorpose/v1/floorpose.pb.h"
#include "platform/dds.h"

namespace floorpose {

class Daemon {
 public:
  explicit Daemon(v1::FloorposedConfig config);
  ~Daemon();

  // Joins DDS, loads the configured plan (a failure there is logged, not fatal: the
  // daemon then waits for a LoadPlan command) and starts the threads.
  bool Start(std::string* error);
  // Wakes and joins both threads; publishes a last status.
  void Stop();

  // Monotonic ns of the io loop's last turn (for the systemd watchdog).
  int64_t last_io_heartbeat_ns() const { return io_heartbeat_ns_.load(); }
  std::string StatusLine() const;

 private:
  struct Job {
    std::vector<Eigen::Vector2d> cloud, normals;
    std::shared_ptr<const ClosestWallIndex> index;  // keeps the plan alive while it runs
    RegistrationOptions options;
    Se2 initial;
    uint64_t version = 0;
    int64_t stamp_ns = 0;
  };
  struct Done {
    Job job;
    RegistrationResult result;
  };

  void IoLoop();
  void WorkerLoop();
  void HandleMeshDelta(const platform::Envelope& e);
  void HandlePose(const platform::Envelope& e);
  void HandleCommand(const platform::Envelope& e);
  void MaybeStartRegistration();
  void ApplyFinishedRegistration();
  std::string LoadPlan(const std::string& path, const std::string& floor);
  void PublishAlignment();
  void PublishStatus(const std::string& message);
  void Publish(platform::Writer& writer, const google::protobuf::Message& msg);
  void Reject(const std::string& why);

  v1::FloorposedConfig config_;
  HeadsetFrame frame_;
  WallExtractionOptions wall_options_;
  std::string device_id_;

  std::unique_ptr<platform::Participant> participant_;
  std::unique_ptr<platform::Reader> mesh_reader_, pose_reader_, command_reader_;
  std::unique_ptr<platform::Writer> plan_pose_writer_, alignment_writer_, status_writer_;
  std::unique_ptr<platform::Waiter> waiter_;

  // Owned by the io thread.
  Tracker tracker_;
  WallStore store_;
  std::string floor_;
  v1::DaemonStatus::Counters counters_;
  struct LastRegistration {
    RegistrationResult result;
    bool accepted = false;
    std::string why;
  };
  std::optional<LastRegistration> last_registration_;
  int64_t latest_stamp_ns_ = 0;
  int64_t next_status_ns_ = 0;
  bool worker_busy_ = false;
  uint64_t last_run_generation_ = 0;  // store generation the last registration saw

  // Io thread <-> worker: one job slot, one result slot (latest wins).
  std::mutex mu_;
  std::condition_variable cv_;
  std::optional<Job> job_;
  std::optional<Done> done_;
  bool stop_ = false;

  std::atomic<bool> running_{false};
  std::atomic<int64_t> io_heartbeat_ns_{0};
  mutable std::mutex status_mu_;
  std::string status_line_;
  std::thread io_thread_, worker_thread_;
};

}  // namespace floorpose
