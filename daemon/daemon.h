// floorposed: the composition root. An io thread owns the DDS readers and the Engine (wall
// store, tracker); a worker thread runs registrations; the caller's (main) thread handles
// signals and systemd.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "daemon/job_slot.h"
#include "daemon/markers_file.h"
#include "daemon/offload.h"
#include "daemon/snapshot_keeper.h"
#include "daemon/status_board.h"
#include "floorpose/v1/config.pb.h"
#include "platform/dds.h"
#include "platform/engine.h"
#include "platform/state_file.h"

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
  // The wearer's inputs of one io turn.
  struct Input {
    platform::Topic topic;
    platform::Envelope envelope;
  };
  void IoLoop();
  void TakeBatch(std::vector<Input>* batch);
  void HandleBatch(const std::vector<Input>& batch);
  void Handle(const Input& in);
  // The daemon's status, with what DDS lost since the last one; the next is due a
  // status period after now_ns.
  void PublishStatus(int64_t now_ns);
  void WorkerLoop();
  // After each input: start a due registration; in deterministic mode wait for it, so
  // the next pose sees its result exactly as `floorpose eval` would.
  void AfterInput();
  void ApplyFinished(bool wait);
  void Publish(platform::Topic topic, const google::protobuf::Message& msg);
  // Crash safety: resume from the snapshot at start (a bad one is set aside), and hand a
  // new one to the SnapshotKeeper when it is due (a new alignment, or new walls).
  void ResumeFromSnapshot();
  // The participant, the readers and writers of the wearer's topics and, where the
  // permissions grant them, the team's; false: why in *error.
  bool JoinDds(std::string* error);
  // The state directory's snapshot (the belief goes on), the keeper that writes the next
  // ones, and the markers.
  void ResumeFromStateDir(const std::string& state_dir);
  void MaybeSnapshot(int64_t now_ns, bool force);

  v1::FloorposedConfig config_;
  bool deterministic_;

  // The participant, the wearer's topics and, where granted, the team's (JoinDds).
  struct Dds {
    std::unique_ptr<platform::Participant> participant;
    std::unique_ptr<platform::Reader> mesh_reader, pose_reader, command_reader;
    // The team's markers, plan poses and statuses (every device's; Engine::OnTeam).
    std::unique_ptr<platform::Reader> marker_reader, team_pose_reader, team_status_reader;
    std::unique_ptr<platform::Writer> plan_pose_writer, alignment_writer, status_writer,
        track_writer, reply_writer, explored_writer, alert_writer, marker_writer;
    std::unique_ptr<platform::Waiter> waiter;
  } dds_;
  std::unique_ptr<platform::Engine> engine_;  // io thread only
  StatusBoard status_;

  JobSlot jobs_;  // io thread <-> worker

  std::unique_ptr<platform::StateDirLock> state_lock_;  // held while the daemon runs
  Offload offload_;                                     // plans loaded by command are built there
  MarkersFile markers_;                                 // state_dir/markers.pb
  std::unique_ptr<SnapshotKeeper> snapshots_;           // null: no state directory

  std::atomic<bool> running_{false};
  std::atomic<int64_t> io_heartbeat_ns_{0};
  std::thread io_thread_, worker_thread_;
};

}  // namespace floorpose
