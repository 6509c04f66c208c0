#include "daemon/daemon.h"

#include <pthread.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <vector>

#include "daemon/scheduling.h"
#include "platform/clock.h"
#include "platform/config.h"
#include "platform/state_file.h"

namespace floorpose {

using platform::Topic;

Daemon::Daemon(v1::FloorposedConfig config)
    : config_(std::move(config)), deterministic_(config_.deterministic()) {}

Daemon::~Daemon() { Stop(); }

bool Daemon::Start(std::string* error) {
  std::string state_dir = config_.state_dir();
  if (const char* systemd_dir = std::getenv("STATE_DIRECTORY"); state_dir.empty() && systemd_dir)
    state_dir = std::string(systemd_dir).substr(0, std::string(systemd_dir).find(':'));
  if (!state_dir.empty()) {
    // Before joining DDS: a second daemon on the same state must not publish at all.
    std::error_code ec;
    std::filesystem::create_directories(state_dir, ec);
    if (ec) spdlog::warn("state directory {}: {}", state_dir, ec.message());
    state_lock_ = platform::StateDirLock::Take(state_dir, error);
    if (!state_lock_) return false;
  }
  // Before DDS starts its receive threads, which inherit it, as the io thread does.
  if (std::string why; !UseShortSlices(&why))
    spdlog::warn("poses keep the kernel's default turns (they may wait on other work): {}", why);
  if (!JoinDds(error)) return false;
  spdlog::info("joined DDS domain {} as device '{}'{}{}", config_.dds().domain_id(),
               config_.dds().device_id(), deterministic_ ? " (deterministic)" : "",
               config_.dds().security().identity_certificate().empty()
                   ? ""
                   : " with DDS Security as " + config_.dds().security().identity_certificate());
  engine_ = std::make_unique<platform::Engine>(
      config_, [this](Topic t, const google::protobuf::Message& m) { Publish(t, m); },
      platform::MonotonicNs);
  if (!deterministic_) {
    engine_->SetOffload([this](std::function<void()> work, std::function<void()> done) {
      offload_.Run(std::move(work), std::move(done), [this] { dds_.waiter->Wake(); });
    });
  }
  const std::string plan_error = engine_->Start();
  if (!state_dir.empty()) ResumeFromStateDir(state_dir);
  engine_->crew().PublishMarkers();
  engine_->PublishStatus(plan_error.empty() ? "started" : plan_error);
  running_ = true;
  io_heartbeat_ns_ = platform::MonotonicNs();
  worker_thread_ = std::thread([this] { WorkerLoop(); });
  io_thread_ = std::thread([this] { IoLoop(); });
  return true;
}

bool Daemon::JoinDds(std::string* error) {
  try {
    const std::optional<platform::DdsSecurity> security = platform::ToDdsSecurity(config_);
    dds_.participant = std::make_unique<platform::Participant>(
        config_.dds().domain_id(), config_.dds().cyclonedds_uri(), security ? &*security : nullptr);
    // Inputs from the default partition (clients written from docs/protocol.md) and the
    // device's own (a headset identity may publish only there: docs/security.md).
    const std::vector<std::string> inputs = {"",
                                             platform::DevicePartition(config_.dds().device_id())};
    dds_.mesh_reader =
        std::make_unique<platform::Reader>(*dds_.participant, Topic::kMeshDelta, inputs);
    dds_.pose_reader =
        std::make_unique<platform::Reader>(*dds_.participant, Topic::kHeadsetPose, inputs);
    dds_.command_reader =
        std::make_unique<platform::Reader>(*dds_.participant, Topic::kCommand, inputs);
    dds_.plan_pose_writer = std::make_unique<platform::Writer>(*dds_.participant, Topic::kPlanPose);
    dds_.alignment_writer =
        std::make_unique<platform::Writer>(*dds_.participant, Topic::kAlignment);
    dds_.status_writer = std::make_unique<platform::Writer>(*dds_.participant, Topic::kStatus);
    dds_.track_writer = std::make_unique<platform::Writer>(*dds_.participant, Topic::kPlanTrack);
    dds_.reply_writer = std::make_unique<platform::Writer>(*dds_.participant, Topic::kCommandReply);
    dds_.explored_writer = std::make_unique<platform::Writer>(*dds_.participant, Topic::kExplored);
    dds_.waiter = std::make_unique<platform::Waiter>(*dds_.participant);
    dds_.waiter->Attach(*dds_.mesh_reader);
    dds_.waiter->Attach(*dds_.pose_reader);
    dds_.waiter->Attach(*dds_.command_reader);
  } catch (const std::exception& e) {
    *error = std::string("DDS: ") + e.what();
    return false;
  }
  try {
    // The team's topics. On a secured domain whose permissions predate them, the daemon
    // still positions its wearer, without alerts, markers and teammates.
    dds_.alert_writer = std::make_unique<platform::Writer>(*dds_.participant, Topic::kAlert);
    dds_.marker_writer = std::make_unique<platform::Writer>(*dds_.participant, Topic::kMarker);
    dds_.marker_reader = std::make_unique<platform::Reader>(*dds_.participant, Topic::kMarker);
    dds_.team_pose_reader = std::make_unique<platform::Reader>(*dds_.participant, Topic::kPlanPose);
    dds_.team_status_reader = std::make_unique<platform::Reader>(*dds_.participant, Topic::kStatus);
    dds_.waiter->Attach(*dds_.marker_reader);
  } catch (const std::exception& e) {
    spdlog::warn(
        "DDS: {}: the team's topics are not granted, so no alerts, markers or teammates "
        "(tools/make-dds-security.sh grants them)",
        e.what());
    dds_.alert_writer.reset();
    dds_.marker_writer.reset();
    dds_.marker_reader.reset();
    dds_.team_pose_reader.reset();
    dds_.team_status_reader.reset();
  }
  return true;
}

void Daemon::ResumeFromStateDir(const std::string& state_dir) {
  snapshots_ = std::make_unique<SnapshotKeeper>(
      platform::SnapshotPath(state_dir, config_.dds().device_id()), config_.snapshot_period_s());
  ResumeFromSnapshot();
  markers_.Open((std::filesystem::path(state_dir) / "markers.pb").string(),
                engine_->crew().markers());
}

void Daemon::Stop() {
  if (!running_.exchange(false)) return;
  jobs_.Stop();
  dds_.waiter->Wake();
  io_thread_.join();
  worker_thread_.join();
  offload_.Join();  // a plan being built is dropped
  if (snapshots_) {
    MaybeSnapshot(platform::MonotonicNs(), /*force=*/true);
    snapshots_->Finish();
  }
  engine_->PublishStatus("stopping");
  const auto& c = engine_->counters();
  spdlog::info("stopped: {} poses in, {} plan poses out, {} mesh deltas, {} rejected", c.poses_in(),
               c.plan_poses_out(), c.mesh_deltas_in(), c.rejected_messages());
}

std::string Daemon::StatusLine() const { return status_.Line(); }

void Daemon::IoLoop() {
  pthread_setname_np(pthread_self(), "fp-io");
  std::vector<Input> batch;
  while (true) {
    dds_.waiter->Wait(std::chrono::milliseconds(100));
    if (jobs_.stopped()) break;
    io_heartbeat_ns_ = platform::MonotonicNs();
    offload_.RunPosted();
    TakeBatch(&batch);
    HandleBatch(batch);
    ApplyFinished(false);
    // The team: at a person's pace, a bounded take a turn is plenty.
    for (auto* reader :
         {dds_.marker_reader.get(), dds_.team_pose_reader.get(), dds_.team_status_reader.get()})
      if (reader)
        for (const platform::Envelope& e : reader->Take(256)) engine_->OnTeam(reader->topic(), e);
    markers_.Save(engine_->crew().markers());
    const int64_t now = platform::MonotonicNs();
    MaybeSnapshot(now, false);
    if (status_.Due(now)) PublishStatus(now);
  }
}

void Daemon::TakeBatch(std::vector<Input>* batch) {
  // One batch from all inputs, in stamp order (platform::InputBefore), the order
  // `floorpose eval` takes a recording in: a pose is corrected with the walls and the
  // pick that came before it. The readers are taken in turn, and again until a turn
  // takes nothing: a message that arrives during a turn, after its reader was taken,
  // may come after messages sent later on another topic that the same turn did take
  // (a pose missed while a wall pick sent after it was taken, under load); Cyclone
  // delivers one peer's messages in the order they were sent, so once a whole turn
  // finds nothing new, nothing sent before a message of the batch is still missing.
  // A peer that never pauses ends the turns after kMaxTurns; its batch is then one
  // turn short of exact, as it would be with a single turn.
  constexpr int kMaxTurns = 8;
  batch->clear();
  for (int turn = 0; turn < kMaxTurns; ++turn) {
    const size_t before = batch->size();
    for (auto* reader : {dds_.pose_reader.get(), dds_.mesh_reader.get(), dds_.command_reader.get()})
      for (auto& e : reader->Take(256)) batch->push_back({reader->topic(), std::move(e)});
    if (batch->size() == before) break;
  }
  std::stable_sort(batch->begin(), batch->end(), [](const Input& a, const Input& b) {
    return platform::InputBefore(a.topic, a.envelope.stamp_ns, b.topic, b.envelope.stamp_ns);
  });
}

void Daemon::Handle(const Input& in) {
  switch (in.topic) {
    case Topic::kCommand: engine_->OnCommand(in.envelope); break;
    case Topic::kMeshDelta: engine_->OnMeshDelta(in.envelope); break;
    default: engine_->OnHeadsetPose(in.envelope); break;
  }
}

void Daemon::HandleBatch(const std::vector<Input>& batch) {
  if (deterministic_) {
    for (const Input& in : batch) {
      if (!running_) break;
      Handle(in);
      AfterInput();
    }
    return;
  }
  // The wearer first: the batch's poses (and commands, in their order) are answered
  // before its meshes become wall points, and a registration is applied and the next
  // one scheduled after them; a pose that arrives meanwhile is answered before the next
  // mesh. Registrations run on the worker, so neither order changes what they see by
  // more than a batch; a pose no longer waits for wall extraction, a store snapshot or
  // a PlanTrack (floorpose bench daemon, p99 latency).
  for (const Input& in : batch)
    if (in.topic != Topic::kMeshDelta) Handle(in);
  for (const Input& in : batch) {
    if (in.topic != Topic::kMeshDelta) continue;
    if (!running_) break;  // SIGTERM does not wait for a flood of meshes
    for (auto& e : dds_.pose_reader->Take(256)) Handle({Topic::kHeadsetPose, std::move(e)});
    Handle(in);
  }
  AfterInput();
}

void Daemon::PublishStatus(int64_t now_ns) {
  // What DDS lost or rejected since the last status, counted in this one.
  for (auto* reader : {dds_.pose_reader.get(), dds_.mesh_reader.get(), dds_.command_reader.get()}) {
    const platform::Reader::Losses l = reader->TakeLosses();
    engine_->OnDdsLosses(reader->topic(), l.lost, l.rejected);
  }
  engine_->PublishStatus({});
  status_.Posted(engine_->StatusLine(),
                 now_ns + static_cast<int64_t>(config_.status_period_s() * 1e9));
}

void Daemon::AfterInput() {
  ApplyFinished(false);
  if (auto job = engine_->TakeDueJob()) {
    jobs_.Put(std::move(*job));
    if (deterministic_) ApplyFinished(true);
  }
}

void Daemon::ApplyFinished(bool wait) {
  if (std::optional<platform::Done> done = jobs_.TakeDone(wait))
    engine_->OnRegistrationDone(std::move(*done));
}

void Daemon::WorkerLoop() {
  // The worker touches nothing of the io thread's but the job, which carries its own
  // copies (the index as a shared_ptr), so a plan change never pulls data from under it.
  // It yields the core to the io thread: a pose is answered before a registration goes
  // on (on a two-core puck shared with other software, the scheduler decides; nice 10
  // gives this thread a tenth of the io thread's weight, and the io thread's short
  // slices let a pose preempt it at once). Not SCHED_IDLE: under load from other
  // processes an idle-class worker starves, and the poses stalled behind it (11 of 40
  // answered in 10 s while CI built beside the tests), most likely on a lock it held.
  pthread_setname_np(pthread_self(), "fp-worker");
  if (std::string why; !UseBackgroundPriority(&why))
    spdlog::warn("registration worker keeps its priority (poses may wait on it): {}", why);
  while (std::optional<platform::Job> job = jobs_.Take()) {
    jobs_.Finish(platform::RunJob(std::move(*job), platform::MonotonicNs));
    dds_.waiter->Wake();
  }
}

void Daemon::Publish(Topic topic, const google::protobuf::Message& msg) {
  platform::Writer* writer = topic == Topic::kPlanPose       ? dds_.plan_pose_writer.get()
                             : topic == Topic::kAlignment    ? dds_.alignment_writer.get()
                             : topic == Topic::kStatus       ? dds_.status_writer.get()
                             : topic == Topic::kPlanTrack    ? dds_.track_writer.get()
                             : topic == Topic::kCommandReply ? dds_.reply_writer.get()
                             : topic == Topic::kExplored     ? dds_.explored_writer.get()
                             : topic == Topic::kAlert        ? dds_.alert_writer.get()
                             : topic == Topic::kMarker       ? dds_.marker_writer.get()
                                                             : nullptr;
  if (!writer) return;
  // A marker is its own instance, keyed by its id; everything else is the device's.
  const std::string& key = topic == Topic::kMarker ? static_cast<const v1::Marker&>(msg).id()
                                                   : config_.dds().device_id();
  std::string error;
  if (!writer->WriteMessage(key, msg, platform::WallClockNs(), &error))
    spdlog::warn("publishing on {} failed: {}", platform::TopicName(topic), error);
}

void Daemon::ResumeFromSnapshot() {
  const std::string& path = snapshots_->path();
  v1::StateSnapshot snapshot;
  std::string error;
  const uint64_t max_bytes = uint64_t{config_.limits().max_snapshot_mb()} << 20;
  switch (platform::ReadStateFile(path, &snapshot, &error, max_bytes)) {
    case platform::StateRead::kMissing:
      spdlog::info("no snapshot at {}: starting clean", path);
      return;
    case platform::StateRead::kBad: break;
    case platform::StateRead::kOk:
      error = engine_->RestoreState(snapshot);
      if (error.empty()) {
        const v1::DaemonStatus s = engine_->Status({});
        const double age_s =
            static_cast<double>(platform::WallClockNs() - snapshot.written_unix_ns()) * 1e-9;
        spdlog::info(
            "resumed from {} (written {:.1f} s ago): alignment version {}, {} meshes, "
            "{} wall points",
            path, age_s, snapshot.alignment().version(), s.live_meshes(), s.wall_points());
        snapshots_->Resumed(snapshot.alignment().version());
        engine_->PublishAlignment();
        return;
      }
      error = "a snapshot " + error;
      break;
  }
  std::string aside_error;
  const std::string aside = platform::SetAside(path, &aside_error);
  spdlog::warn("snapshot {} not trusted: {}; {}; starting clean", path, error,
               aside.empty() ? aside_error : "set aside as " + aside);
}

void Daemon::MaybeSnapshot(int64_t now_ns, bool force) {
  if (!snapshots_) return;
  const uint64_t version = engine_->alignment().version;
  const uint64_t deltas = engine_->counters().mesh_deltas_in();
  if (!snapshots_->Due(version, deltas, now_ns, force)) return;
  v1::StateSnapshot snapshot = engine_->SaveState();
  snapshot.set_written_unix_ns(platform::WallClockNs());
  snapshots_->Write(std::move(snapshot), version, deltas, now_ns);
}

}  // namespace floorpose
