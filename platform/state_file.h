// The daemon's state snapshot on disk (state_dir): written atomically (a temporary file
// beside it, fsync, rename, fsync of the directory), so a crash or a power cut leaves the
// old snapshot or the new one, never half of one; and checked on reading (a magic, the
// length and a CRC-32 of the payload), so a corrupt or foreign file is never trusted.
#pragma once

#include <google/protobuf/message_lite.h>

#include <cstdint>
#include <memory>
#include <string>

namespace floorpose::platform {

bool WriteStateFile(const std::string& path, const google::protobuf::MessageLite& message,
                    std::string* error);

enum class StateRead { kOk, kMissing, kBad };
// kMissing: no file (a first start). kBad: *error says what is wrong with it. Only a
// regular file of at most max_bytes is read: a link, a directory, a FIFO or a device is
// refused without following, blocking on or reading it.
StateRead ReadStateFile(const std::string& path, google::protobuf::MessageLite* message,
                        std::string* error, uint64_t max_bytes = uint64_t{1} << 30);

// Moves a file that must not be trusted out of the way, as <path>.bad-<unix seconds>, for
// a person to look at. Returns its new name, or empty with *error.
std::string SetAside(const std::string& path, std::string* error);

// One floorposed per state directory: an exclusive lock on <dir>/floorposed.lock, held
// while this object lives (the kernel drops it when the process dies, even by SIGKILL).
class StateDirLock {
 public:
  // Takes the lock; on failure *error says why, naming the holder's pid when it can.
  static std::unique_ptr<StateDirLock> Take(const std::string& dir, std::string* error);
  ~StateDirLock();
  StateDirLock(const StateDirLock&) = delete;
  StateDirLock& operator=(const StateDirLock&) = delete;

 private:
  explicit StateDirLock(int fd) : fd_(fd) {}
  int fd_;
};

// <dir>/<device id>.snapshot, the device id reduced to [A-Za-z0-9._-].
std::string SnapshotPath(const std::string& dir, const std::string& device_id);

}  // namespace floorpose::platform
