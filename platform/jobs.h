// The worker's jobs: an update of the belief or a search of the whole plan, which is due,
// what a job carries (everything copied, so that it runs on any thread), and running one.
// The io thread takes a due job (JobScheduler) and applies its result (Engine); RunJob is
// all the worker does.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/closest_wall_index.h"
#include "core/global_search.h"
#include "core/registration.h"
#include "core/tracking/mcl.h"
#include "core/wall_store.h"
#include "platform/plan_assets.h"
#include "platform/search_memory.h"

namespace floorpose::platform {

struct Job {
  std::vector<Eigen::Vector2d> cloud;  // the window's wall points, slam frame
  std::shared_ptr<const ClosestWallIndex> index;
  Se2 initial;           // the alignment in use (a search refines it with its places)
  uint64_t version = 0;  // ...and its version (0: none)
  int64_t stamp_ns = 0;
  // Set: search the whole plan for the cloud, then refine the places on `index` with
  // `icp`, as `refine` says, on the wearer's slam positions over the same window.
  std::shared_ptr<GlobalSearchCache> global;
  IcpOptions icp;
  RefineOptions refine;
  std::vector<Eigen::Vector2d> path;
  // Else: an update of the belief on `cloud`.
  std::optional<tracking::MclUpdate> mcl;
  tracking::MclOptions mcl_options;
};

struct Done {
  Job job;
  RegistrationResult result;        // the update's polish (time_ms: the whole job's)
  std::vector<GlobalPlace> places;  // of a search, best first...
  double search_cpu_s = 0;          // ...and its CPU at the nominal cost (SearchBudget)
  std::optional<tracking::MclUpdateResult> mcl;  // of an update
};

// Runs a job; now_ns() is read before and after to fill result.time_ms.
Done RunJob(Job job, const std::function<int64_t()>& now_ns);
// Places refined and ranked on a search job's walls and path, as RunJob does with the
// search's own (the tools score the true place this way). `ranked`: places it returned
// before on this job, ranked with the new ones.
std::vector<GlobalPlace> RefineAsSearch(const Job& job, const std::vector<GlobalPlace>& places,
                                        const std::vector<GlobalPlace>& ranked = {});

// The plan's searches' share of a core (limits.search_cpu), averaged over kHorizonS: a
// token bucket that holds what the share earns in that time, full at the start, and lets a
// search start while it is not in debt. A search is priced by its branch and bound's point
// lookups at a nominal cost per lookup, not by a clock, so that a replay searches where it
// did before on any machine and under any load (the refinement of its places is in the
// nominal cost: docs/performance.md).
class SearchBudget {
 public:
  static constexpr double kHorizonS = 600.0;
  static constexpr double kNsPerPointBound = 2.5;
  static double CpuS(double point_bounds) { return point_bounds * kNsPerPointBound * 1e-9; }

  explicit SearchBudget(double share) : share_(share), credit_s_(share * kHorizonS) {}
  bool Allows(int64_t now_ns) {
    Refill(now_ns);
    return share_ > 0 && credit_s_ >= 0;
  }
  void Spend(double cpu_s, int64_t now_ns) {
    Refill(now_ns);
    credit_s_ -= cpu_s;
  }

 private:
  void Refill(int64_t now_ns);

  double share_;
  double credit_s_;  // CPU seconds the searches may still take; below 0 a debt
  std::optional<int64_t> last_ns_;
};

// One job at a time: which is due, from the tracker and the wall store as they are now.
class JobScheduler {
 public:
  explicit JobScheduler(double search_cpu) : budget_(search_cpu) {}
  // A pose's slam position, for the path the searches weigh.
  void AddPosition(int64_t stamp_ns, const Eigen::Vector2d& position, double window_s) {
    searches_.AddPosition(stamp_ns, position, window_s);
  }
  // The job due at `now_ns` (the device's newest stamp), if none is running: a search
  // of the plan (with `global`, when the tracker asks for one and the walls are new), else
  // an update of the belief; at most window_max_points wall points.
  std::optional<Job> TakeDue(tracking::MclTracker& tracker, WallStore& store,
                             const std::shared_ptr<GlobalSearchCache>& global,
                             size_t window_max_points, int64_t now_ns);
  // The running job ended; a search's CPU comes off the budget at its stamp.
  void Finished(const Done& done) {
    running_ = false;
    if (done.job.global) budget_.Spend(done.search_cpu_s, done.job.stamp_ns);
  }
  bool running() const { return running_; }

  // The latest update's polish, whether the tracker took it, and why not.
  struct LastUpdate {
    RegistrationResult result;
    bool accepted = false;
    std::string why;
  };
  void SetLast(LastUpdate last) { last_ = std::move(last); }
  const std::optional<LastUpdate>& last() const { return last_; }

 private:
  SearchMemory searches_;  // the path and walls of the plan's searches
  SearchBudget budget_;
  std::optional<LastUpdate> last_;
  bool running_ = false;
};

}  // namespace floorpose::platform
