#include "platform/jobs.h"

#include <algorithm>

namespace floorpose::platform {

std::vector<GlobalPlace> RefineAsSearch(const Job& job, const std::vector<GlobalPlace>& places,
                                        const std::vector<GlobalPlace>& ranked) {
  if (!job.global || !job.index) return {};
  const GlobalSearch& search = job.global->Get();
  RefineOptions refine = job.refine;  // places are one place as the search has them
  refine.distinct_m = search.options().distinct_m;
  refine.distinct_rad = search.options().distinct_rad;
  return RefinePlaces(places, job.cloud, job.path, *job.index, job.icp, refine, ranked);
}

Done RunJob(Job job, const std::function<int64_t()>& now_ns) {
  Done done;
  const int64_t t0 = now_ns();
  if (job.global) {
    const GlobalSearch& search = job.global->Get();
    const std::vector<double> headings = search.WallHeadings(job.cloud);
    GlobalSearchStats stats;
    done.places = search.Search(job.cloud, headings, &stats);
    double point_bounds = stats.point_bounds();
    if (job.version > 0) done.places.push_back({job.initial});  // the place in use, refined too
    if (job.index) done.places = RefineAsSearch(job, done.places);
    if (job.refine.alike_reach_m > 0 && !done.places.empty() && done.places.front().rank == 0) {
      // The best's half-turn twin, refined and ranked with the others: the grid's few
      // places often lack it, and the belief must hold both while the walls cannot tell.
      WallSampleOptions in_sight;
      in_sight.reach_m = job.refine.alike_reach_m;
      in_sight.end_margin_m = job.refine.path_margin_m;
      // Stats of their own: no walls in sight under the place, and there is no search.
      GlobalSearchStats twin_stats;
      const std::vector<GlobalPlace> twins =
          HalfTurnTwins(search, job.index->plan(), done.places.front().T_plan_slam, job.path,
                        headings, in_sight, &twin_stats);
      point_bounds += twin_stats.point_bounds();
      if (!twins.empty()) done.places = RefineAsSearch(job, twins, done.places);
    }
    done.result.points = static_cast<uint32_t>(job.cloud.size());
    done.search_cpu_s = SearchBudget::CpuS(point_bounds);
  } else if (job.mcl && job.index) {
    done.mcl = tracking::RunMclUpdate(std::move(*job.mcl), job.cloud, *job.index, job.mcl_options);
    job.mcl.reset();
    done.result = done.mcl->icp;
  } else {
    done.result.reason = "no floor plan";
  }
  done.result.time_ms = static_cast<double>(now_ns() - t0) * 1e-6;
  done.job = std::move(job);
  return done;
}

void SearchBudget::Refill(int64_t now_ns) {
  // A stamp before the last (the headset's clock started again) earns nothing, and the
  // budget goes on from it.
  if (last_ns_ && now_ns > *last_ns_)
    credit_s_ = std::min(share_ * kHorizonS,
                         credit_s_ + share_ * static_cast<double>(now_ns - *last_ns_) * 1e-9);
  last_ns_ = now_ns;
}

std::optional<Job> JobScheduler::TakeDue(tracking::MclTracker& tracker, WallStore& store,
                                         const std::shared_ptr<GlobalSearchCache>& global,
                                         size_t window_max_points, int64_t now) {
  if (running_) return std::nullopt;
  const tracking::MclOptions& options = tracker.options();
  // Wall points from before a loss of tracking are in another frame.
  const auto since = [&](double window_s) {
    return std::max(tracker.frame_since_ns(),
                    window_s > 0 ? now - static_cast<int64_t>(window_s * 1e9) : INT64_MIN);
  };
  if (global && budget_.Allows(now) && tracker.SearchDue(now, store.points())) {
    // Where on the whole plan do the walls fit: to seed the belief, or to reseed it. A
    // look that finds fewer than search_min_points in the window counts as a search: the
    // next comes a search interval later and runs on that interval's walls too. (Looking
    // again as soon as the window holds the least places the wearer sooner, and more often
    // wrongly: docs/evaluation.md, "Why these defaults".)
    tracker.MarkSearchStarted(now);
    const int64_t from = since(options.search_window_s);
    Job job;
    job.cloud = store.Snapshot(window_max_points, from);
    // Nothing scanned or dropped since the last search (the wearer stands, or walks where
    // the headset has meshed everything): the same places again, no new evidence.
    if (job.cloud.size() >= options.search_min_points &&
        searches_.NewSearch(job.cloud, tracker.alignment().version)) {
      job.path = searches_.PathSince(from);
      job.global = global;
      job.index = tracker.index();
      job.icp = options.icp;
      job.refine = options.refine;
      job.initial = tracker.alignment().T_plan_slam;
      job.version = tracker.alignment().version;
      job.stamp_ns = now;
      running_ = true;
      return job;
    }
  }
  if (!tracker.UpdateDue(now, store.points())) return std::nullopt;
  Job job;
  job.cloud = store.Snapshot(window_max_points, since(options.window_s));
  if (job.cloud.size() < options.min_points) return std::nullopt;
  store.TakeNewPoints();
  const int64_t fresh_since =
      std::max(since(options.window_s), tracker.last_update_ns().value_or(INT64_MIN));
  std::vector<Eigen::Vector2d> fresh = store.Snapshot(window_max_points, fresh_since);
  job.mcl = tracker.PrepareUpdate(now);
  job.mcl->fresh_slam = std::move(fresh);
  job.mcl->sight_slam = searches_.PathBetween(
      since(options.window_s), now - static_cast<int64_t>(tracking::kMeshLatencyS * 1e9));
  job.mcl_options = options;
  job.index = tracker.index();
  job.version = tracker.alignment().version;
  job.stamp_ns = now;
  running_ = true;
  return job;
}

}  // namespace floorpose::platform
