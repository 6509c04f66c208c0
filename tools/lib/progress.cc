#include "tools/lib/progress.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <thread>
#include <vector>

namespace floorpose::tools {
namespace {

std::string Duration(double s) {
  char text[32];
  if (s < 60)
    std::snprintf(text, sizeof(text), "%.0f s", s);
  else
    std::snprintf(text, sizeof(text), "%d min %02d s", static_cast<int>(s) / 60,
                  static_cast<int>(s) % 60);
  return text;
}

}  // namespace

bool Progress::OnTerminal() { return isatty(STDERR_FILENO) == 1; }

Progress::Progress(std::string label, size_t total, std::string unit)
    : label_(std::move(label)),
      total_(total),
      unit_(unit.empty() ? std::string() : std::string(" ").append(unit)),
      terminal_(OnTerminal()),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

Progress::~Progress() {
  std::lock_guard lock(mu_);
  if (!terminal_) return;
  Draw(done_);
  std::fputc('\n', stderr);
}

void Progress::Update(size_t done) {
  std::lock_guard lock(mu_);
  done_ = done;
  if (!terminal_) return;
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && now - last_ < std::chrono::milliseconds(500) && (total_ == 0 || done < total_))
    return;
  last_ = now;
  Draw(done);
}

void Progress::Clear() {
  std::lock_guard lock(mu_);
  if (!terminal_ || !drawn_) return;
  std::fputs("\r\033[K", stderr);
  drawn_ = false;
}

void Progress::Draw(size_t done) {
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::string text = "\r\033[K" + label_ + ": " + std::to_string(done) +
                     (total_ ? " / " + std::to_string(total_) : std::string()) + unit_ + ", " +
                     Duration(elapsed);
  if (done > 0 && done < total_)
    text += ", about " +
            Duration(elapsed / static_cast<double>(done) * static_cast<double>(total_ - done)) +
            " left";
  std::fputs(text.c_str(), stderr);
  std::fflush(stderr);
  drawn_ = true;
}

void ParallelFor(size_t n, int jobs, const std::string& label,
                 const std::function<void(size_t item, Progress& progress)>& fn) {
  Progress progress(label, n);
  std::atomic<size_t> next{0}, done{0};
  auto worker = [&] {
    for (size_t i = next++; i < n; i = next++) {
      fn(i, progress);
      progress.Update(++done);
    }
  };
  const unsigned threads =
      jobs > 0 ? static_cast<unsigned>(jobs) : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (unsigned j = 0; j < threads; ++j) pool.emplace_back(worker);
  for (std::thread& t : pool) t.join();
}

}  // namespace floorpose::tools
