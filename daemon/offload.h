// Work the io thread hands off (a plan loaded by command is built off it): one thread at
// a time runs the work, and what then goes on on the io thread waits until it takes it
// (Engine::SetOffload).
#pragma once

#include <functional>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace floorpose {

class Offload {
 public:
  ~Offload() { Join(); }

  // Runs work() on a thread of its own (after the last one ended), then queues done and
  // calls wake() so that the io thread comes round to it.
  void Run(std::function<void()> work, std::function<void()> done, std::function<void()> wake) {
    Join();  // the last one, done already
    thread_ =
        std::thread([this, work = std::move(work), done = std::move(done), wake = std::move(wake)] {
          work();
          {
            std::lock_guard lock(mu_);
            posted_.push_back(done);
          }
          wake();
        });
  }
  // The io thread: runs what finished work left for it.
  void RunPosted() {
    std::vector<std::function<void()>> posted;
    {
      std::lock_guard lock(mu_);
      posted.swap(posted_);
    }
    for (auto& f : posted) f();
  }
  // Waits for the work under way; what it posts is not run.
  void Join() {
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::thread thread_;
  std::mutex mu_;
  std::vector<std::function<void()>> posted_;
};

}  // namespace floorpose
