// The daemon's latest status line, read by the main thread (systemd's STATUS=), and when
// the io thread publishes the next status.
#pragma once

#include <cstdint>
#include <mutex>
#include <string>
#include <utility>

namespace floorpose {

class StatusBoard {
 public:
  // The io thread: whether a status is due at now_ns.
  bool Due(int64_t now_ns) const { return now_ns >= next_ns_; }
  // The io thread: the status just published; the next is due at next_ns.
  void Posted(std::string line, int64_t next_ns) {
    next_ns_ = next_ns;
    std::lock_guard lock(mu_);
    line_ = std::move(line);
  }
  // Any thread: the latest line.
  std::string Line() const {
    std::lock_guard lock(mu_);
    return line_;
  }

 private:
  int64_t next_ns_ = 0;  // io thread only
  mutable std::mutex mu_;
  std::string line_;
};

}  // namespace floorpose
