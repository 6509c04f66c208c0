// The daemon's crash safety: when a state snapshot is due, and a thread that writes the
// latest one (serialise, fsync, rename) so that the io thread only copies the state.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "floorpose/v1/floorpose.pb.h"

namespace floorpose {

class SnapshotKeeper {
 public:
  // Snapshots go to `path`; new walls alone make one due every period_s.
  SnapshotKeeper(std::string path, double period_s);
  ~SnapshotKeeper();  // Finish()
  SnapshotKeeper(const SnapshotKeeper&) = delete;
  SnapshotKeeper& operator=(const SnapshotKeeper&) = delete;

  const std::string& path() const { return path_; }
  // The daemon resumed from a snapshot of this alignment version: it is saved already.
  void Resumed(uint64_t alignment_version) { saved_version_ = alignment_version; }
  // Whether a snapshot is due at now_ns, given the alignment version and the mesh deltas
  // seen: a new alignment within a second (it is what a restart must not lose), new walls
  // only every period (a restart re-scans them anyway), anything new on force.
  bool Due(uint64_t version, uint64_t deltas, int64_t now_ns, bool force) const;
  // Hands a snapshot of that version and deltas to the writer (the latest wins).
  void Write(v1::StateSnapshot snapshot, uint64_t version, uint64_t deltas, int64_t now_ns);
  // Writes what is pending and joins the writer.
  void Finish();

 private:
  void WriterLoop();

  const std::string path_;
  const int64_t period_ns_;
  uint64_t saved_version_ = 0, saved_deltas_ = 0;  // what the latest snapshot had seen
  int64_t last_ns_ = INT64_MIN / 2;                // monotonic; none yet
  std::mutex mu_;
  std::condition_variable cv_;
  std::optional<v1::StateSnapshot> pending_;
  bool stop_ = false;
  std::thread writer_;
};

}  // namespace floorpose
