// Io thread <-> registration worker: one job slot and one result slot (the latest wins in
// each), and the stop that ends both threads' loops.
#pragma once

#include <condition_variable>
#include <mutex>
#include <optional>
#include <utility>

#include "platform/jobs.h"

namespace floorpose {

class JobSlot {
 public:
  // The io thread: a job for the worker, in place of one it has not taken yet.
  void Put(platform::Job job) {
    {
      std::lock_guard lock(mu_);
      job_ = std::move(job);
    }
    cv_.notify_all();
  }
  // The worker: the next job, waiting for one; nothing once stopped.
  std::optional<platform::Job> Take() {
    std::unique_lock lock(mu_);
    cv_.wait(lock, [&] { return stop_ || job_.has_value(); });
    if (stop_) return std::nullopt;
    std::optional<platform::Job> job = std::move(job_);
    job_.reset();
    return job;
  }
  // The worker: a job's result, in place of one the io thread has not taken yet.
  void Finish(platform::Done done) {
    {
      std::lock_guard lock(mu_);
      done_ = std::move(done);
    }
    cv_.notify_all();
  }
  // The io thread: the latest result, if any, waiting for one when asked (until stopped).
  std::optional<platform::Done> TakeDone(bool wait) {
    std::unique_lock lock(mu_);
    if (wait) cv_.wait(lock, [&] { return stop_ || done_.has_value(); });
    std::optional<platform::Done> done;
    done.swap(done_);
    return done;
  }
  void Stop() {
    {
      std::lock_guard lock(mu_);
      stop_ = true;
    }
    cv_.notify_all();
  }
  bool stopped() {
    std::lock_guard lock(mu_);
    return stop_;
  }

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  std::optional<platform::Job> job_;
  std::optional<platform::Done> done_;
  bool stop_ = false;
};

}  // namespace floorpose
