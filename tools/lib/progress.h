// How far a long command is, on a terminal: "label: done / total, elapsed, about N left"
// rewritten in place on standard error, at most twice a second. Quiet when standard error
// is not a terminal (CI, pipes, files), so logs and tables stay clean.
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <mutex>
#include <string>

namespace floorpose::tools {

class Progress {
 public:
  // total 0: not known beforehand (then only the count and the time are shown).
  Progress(std::string label, size_t total, std::string unit = {});
  static bool OnTerminal();
  ~Progress();  // ends the line it drew
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // `done` of the total are finished (thread-safe).
  void Update(size_t done);
  // Before printing a line of one's own on standard output or error.
  void Clear();
  bool shown() const { return terminal_; }

 private:
  void Draw(size_t done);  // with mu_ held

  std::string label_;
  size_t total_;
  std::string unit_;
  bool terminal_;
  std::chrono::steady_clock::time_point start_, last_;
  size_t done_ = 0;
  bool drawn_ = false;
  std::mutex mu_;
};

// Runs fn(0) .. fn(n - 1) on `jobs` threads (0: one per core), items in order of start,
// showing a Progress labelled `label`. fn must be thread-safe; `progress` lets it clear
// the line before it prints.
void ParallelFor(size_t n, int jobs, const std::string& label,
                 const std::function<void(size_t item, Progress& progress)>& fn);

}  // namespace floorpose::tools
