// A child process (floorposed) started and stopped by the tools and the tests.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace floorpose::tools {

class ChildProcess {
 public:
  // Starts argv[0] with the given arguments; stdout/stderr go to log_path when given.
  ChildProcess(const std::vector<std::string>& argv, const std::string& log_path = "");
  ~ChildProcess();  // SIGKILL if still running
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  bool started() const { return pid_ > 0; }
  pid_t pid() const { return pid_; }
  bool Running();
  // SIGTERM, then wait up to timeout; SIGKILL after. Returns the exit code, or nothing if
  // it had to be killed or died by a signal.
  std::optional<int> Terminate(std::chrono::milliseconds timeout);
  // Waits up to timeout for it to exit on its own (SIGKILL after). The exit code, or
  // nothing if it had to be killed or died by a signal.
  std::optional<int> Wait(std::chrono::milliseconds timeout);
  // SIGKILL now (a crash or a power cut, as far as the child can tell), and reap it.
  void Kill();
  // How long the last Terminate() took.
  std::chrono::milliseconds last_stop_time() const { return stop_time_; }

 private:
  std::optional<int> Reap(bool block);
  std::optional<int> Stop(std::chrono::milliseconds timeout, bool terminate);
  pid_t pid_ = -1;
  std::optional<int> exit_code_;
  bool exited_ = false;
  std::chrono::milliseconds stop_time_{0};
};

// What /proc says of a process now.
struct ProcSample {
  double rss_mb = 0, hwm_mb = 0;  // VmRSS, VmHWM
  double cpu_s = 0;               // utime + stime
};
ProcSample SampleProcess(pid_t pid);
// The fields of a /proc/PID/stat or /proc/PID/task/TID/stat file, field n (numbered from 1
// as in proc(5)) at [n - 1]; the command name, which may hold spaces, is one field. Empty
// when the file cannot be read.
std::vector<std::string> ProcStatFields(const std::string& path);

// floorposed beside this executable (build tree: ../daemon/floorposed) or $FLOORPOSED.
std::string FindFloorposed();

}  // namespace floorpose::tools
