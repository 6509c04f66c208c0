#include "tools/lib/process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <thread>

namespace floorpose::tools {

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const std::string& log_path) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_ = fork();
  if (pid_ == 0) {
    // The child must not inherit blocked signals, or SIGTERM would never reach it.
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    // A tool or test that dies without stopping it (Ctrl-C, a crash) takes it along.
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (!log_path.empty()) {
      const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) {
        dup2(fd, STDOUT_FILENO);
        dup2(fd, STDERR_FILENO);
        close(fd);
      }
    }
    execvp(args[0], args.data());
    _exit(127);
  }
}

ChildProcess::~ChildProcess() { Kill(); }

void ChildProcess::Kill() {
  if (pid_ > 0 && !exited_) {
    kill(pid_, SIGKILL);
    Reap(true);
  }
}

std::optional<int> ChildProcess::Reap(bool block) {
  int status = 0;
  const pid_t r = waitpid(pid_, &status, block ? 0 : WNOHANG);
  if (r == pid_) {
    exited_ = true;
    if (WIFEXITED(status)) exit_code_ = WEXITSTATUS(status);
  }
  return exit_code_;
}

bool ChildProcess::Running() {
  if (pid_ <= 0 || exited_) return false;
  Reap(false);
  return !exited_;
}

std::optional<int> ChildProcess::Wait(std::chrono::milliseconds timeout) {
  return Stop(timeout, false);
}

std::optional<int> ChildProcess::Terminate(std::chrono::milliseconds timeout) {
  return Stop(timeout, true);
}

std::optional<int> ChildProcess::Stop(std::chrono::milliseconds timeout, bool terminate) {
  if (pid_ <= 0) return std::nullopt;
  const auto start = std::chrono::steady_clock::now();
  if (!exited_ && terminate) kill(pid_, SIGTERM);
  while (!exited_ && std::chrono::steady_clock::now() - start < timeout) {
    Reap(false);
    if (!exited_) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  stop_time_ = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::steady_clock::now() - start);
  if (!exited_) {
    kill(pid_, SIGKILL);
    Reap(true);
    return std::nullopt;
  }
  return exit_code_;
}

ProcSample SampleProcess(pid_t pid) {
  ProcSample s;
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string key;
  double kb = 0;
  std::string line;
  while (std::getline(status, line)) {
    std::istringstream in(line);
    if (!(in >> key >> kb)) continue;
    if (key == "VmRSS:") s.rss_mb = kb / 1024.0;
    if (key == "VmHWM:") s.hwm_mb = kb / 1024.0;
  }
  const std::vector<std::string> stat = ProcStatFields("/proc/" + std::to_string(pid) + "/stat");
  if (stat.size() < 15) return s;
  const double utime = std::stod(stat[13]), stime = std::stod(stat[14]);
  s.cpu_s = (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
  return s;
}

std::vector<std::string> ProcStatFields(const std::string& path) {
  std::ifstream stat(path);
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  const size_t open = text.find('('), close = text.rfind(')');
  if (open == std::string::npos || close == std::string::npos || close < open) return {};
  std::vector<std::string> fields{text.substr(0, open - 1),
                                  text.substr(open + 1, close - open - 1)};
  std::istringstream rest(text.substr(close + 1));
  for (std::string field; rest >> field;) fields.push_back(field);
  return fields;
}

std::string FindFloorposed() {
  if (const char* env = std::getenv("FLOORPOSED")) return env;
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec).parent_path();
  for (const auto& candidate : {self / "floorposed", self / ".." / "daemon" / "floorposed",
                                self / ".." / ".." / "daemon" / "floorposed"}) {
    if (std::filesystem::exists(candidate, ec))
      return std::filesystem::weakly_canonical(candidate, ec).string();
  }
  return "floorposed";  // then execvp searches PATH (an installed floorposed)
}

}  // namespace floorpose::tools
