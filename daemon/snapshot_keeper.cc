#include "daemon/snapshot_keeper.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <utility>

#include "platform/clock.h"
#include "platform/state_file.h"

namespace floorpose {

SnapshotKeeper::SnapshotKeeper(std::string path, double period_s)
    : path_(std::move(path)),
      period_ns_(static_cast<int64_t>(period_s * 1e9)),
      writer_([this] { WriterLoop(); }) {}

SnapshotKeeper::~SnapshotKeeper() { Finish(); }

bool SnapshotKeeper::Due(uint64_t version, uint64_t deltas, int64_t now_ns, bool force) const {
  const bool new_alignment = version != saved_version_, new_walls = deltas != saved_deltas_;
  if (!new_alignment && !new_walls) return false;
  const int64_t due_ns =
      last_ns_ + (new_alignment ? std::min<int64_t>(1'000'000'000, period_ns_) : period_ns_);
  return force || now_ns >= due_ns;
}

void SnapshotKeeper::Write(v1::StateSnapshot snapshot, uint64_t version, uint64_t deltas,
                           int64_t now_ns) {
  saved_version_ = version;
  saved_deltas_ = deltas;
  last_ns_ = now_ns;
  {
    std::lock_guard lock(mu_);
    pending_ = std::move(snapshot);
  }
  cv_.notify_one();
}

void SnapshotKeeper::Finish() {
  if (!writer_.joinable()) return;
  {
    std::lock_guard lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  writer_.join();  // writes what is pending first
}

void SnapshotKeeper::WriterLoop() {
  while (true) {
    v1::StateSnapshot snapshot;
    {
      std::unique_lock lock(mu_);
      cv_.wait(lock, [&] { return stop_ || pending_.has_value(); });
      if (!pending_) return;  // stopping with nothing left to write
      snapshot = std::move(*pending_);
      pending_.reset();
    }
    std::string error;
    const int64_t t0 = platform::MonotonicNs();
    if (platform::WriteStateFile(path_, snapshot, &error)) {
      spdlog::debug("snapshot: alignment version {}, {} meshes, written in {:.1f} ms",
                    snapshot.alignment().version(), snapshot.meshes_size(),
                    static_cast<double>(platform::MonotonicNs() - t0) * 1e-6);
    } else {
      spdlog::warn("snapshot not written: {}", error);
    }
  }
}

}  // namespace floorpose
