// Engine's worker jobs (platform/engine.h): what is due, what it runs on, and what its
// result changes. The io thread takes a job and finishes it; Run is all the worker does.
#include <spdlog/spdlog.h>

#include <algorithm>

#include "platform/engine.h"

namespace floorpose::platform {

std::vector<GlobalPlace> Engine::RefineAsSearch(const Job& job,
                                                const std::vector<GlobalPlace>& places,
                                                const std::vector<GlobalPlace>& ranked) {
  if (!job.global || !job.index) return {};
  const GlobalSearch& search = job.global->Get();
  RefineOptions refine = job.refine;  // places are one place as the search has them
  refine.distinct_m = search.options().distinct_m;
  refine.distinct_rad = search.options().distinct_rad;
  return RefinePlaces(places, job.cloud, job.path, *job.index, job.icp, refine, ranked);
}

Engine::Done Engine::Run(Job job, const std::function<int64_t()>& now_ns) {
  Done done;
  const int64_t t0 = now_ns();
  if (job.global) {
    const GlobalSearch& search = job.global->Get();
    const std::vector<double> headings = search.WallHeadings(job.cloud);
    done.places = search.Search(job.cloud, headings);
    if (job.version > 0) done.places.push_back({job.initial});  // the place in use, refined too
    if (job.index) done.places = RefineAsSearch(job, done.places);
    if (job.refine.alike_reach_m > 0 && !done.places.empty() && done.places.front().rank == 0) {
      // The best's half-turn twin, refined and ranked with the others: the grid's few
      // places often lack it, and the belief must hold both while the walls cannot tell.
      WallSampleOptions in_sight;
      in_sight.reach_m = job.refine.alike_reach_m;
      in_sight.end_margin_m = job.refine.path_margin_m;
      const std::vector<GlobalPlace> twins = HalfTurnTwins(
          search, job.index->plan(), done.places.front().T_plan_slam, job.path, headings, in_sight);
      if (!twins.empty()) done.places = RefineAsSearch(job, twins, done.places);
    }
    done.result.points = static_cast<uint32_t>(job.cloud.size());
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

std::optional<Engine::Job> Engine::SearchJob(int64_t since, size_t min_points) {
  Job job;
  job.cloud = store_.Snapshot(config_.walls().window_max_points(), since);
  if (job.cloud.size() < min_points) return std::nullopt;
  // Nothing scanned or dropped since the last search (the wearer stands, or walks
  // where the headset has meshed everything): the same places again, no new evidence.
  if (!searches_.NewSearch(job.cloud, alignment().version)) return std::nullopt;
  job.path = searches_.PathSince(since);
  job.global = plans_.current().global;
  job.index = tracker_.index();
  job.icp = tracker_.options().icp;
  job.refine = tracker_.options().refine;
  job.initial = alignment().T_plan_slam;
  job.version = alignment().version;
  job.stamp_ns = intake_.clock().newest_ns();
  return job;
}

std::optional<Engine::Job> Engine::TakeDueJob() {
  if (running_) return std::nullopt;
  const int64_t now = intake_.clock().newest_ns();
  const tracking::MclOptions& options = tracker_.options();
  // Wall points from before a loss of tracking are in another frame.
  const auto since = [&](double window_s) {
    return std::max(tracker_.frame_since_ns(),
                    window_s > 0 ? now - static_cast<int64_t>(window_s * 1e9) : INT64_MIN);
  };
  if (plans_.current().global && tracker_.SearchDue(now, store_.points())) {
    // Where on the whole plan do the walls fit: to seed the belief, or to reseed it.
    tracker_.MarkSearchStarted(now);
    std::optional<Job> job = SearchJob(since(options.search_window_s), options.search_min_points);
    if (job) {
      running_ = true;
      return job;
    }
  }
  if (!tracker_.UpdateDue(now, store_.points())) return std::nullopt;
  Job job;
  job.cloud = store_.Snapshot(config_.walls().window_max_points(), since(options.window_s));
  if (job.cloud.size() < options.min_points) return std::nullopt;
  store_.TakeNewPoints();
  const int64_t fresh_since =
      std::max(since(options.window_s), tracker_.last_update_ns().value_or(INT64_MIN));
  std::vector<Eigen::Vector2d> fresh =
      store_.Snapshot(config_.walls().window_max_points(), fresh_since);
  job.mcl = tracker_.PrepareUpdate(now);
  job.mcl->fresh_slam = std::move(fresh);
  job.mcl_options = options;
  job.index = tracker_.index();
  job.version = alignment().version;
  job.stamp_ns = now;
  running_ = true;
  return job;
}

void Engine::OnRegistrationDone(Done done) {
  running_ = false;
  if (done.job.global) {
    const std::string what = tracker_.OfferPlaces(done.places, done.job.stamp_ns);
    spdlog::info("global search: {} points, {} place(s), {:.1f} ms: {}", done.job.cloud.size(),
                 done.places.size(), done.result.time_ms, what);
    PublishAlignment();
    return;
  }
  if (!done.mcl) return;
  intake_.counters().set_registrations(intake_.counters().registrations() + 1);
  const size_t samples = done.mcl->belief.size(), places = done.mcl->places;
  const double fit = done.mcl->fit;
  const bool polished = done.mcl->polished;
  const bool taken = tracker_.FinishUpdate(std::move(*done.mcl), done.job.stamp_ns);
  const Reliability r = tracker_.CurrentReliability();
  last_registration_ = {done.result, taken, taken ? r.reason : "a new prior came meanwhile"};
  spdlog::info("belief: {} samples, {} place(s), fit {:.2f}, polished {}, {:.1f} ms: {:.0f}% {}",
               samples, places, fit, polished, done.result.time_ms, 100 * r.probability, r.reason);
  if (!taken) return;
  intake_.counters().set_registrations_accepted(intake_.counters().registrations_accepted() + 1);
  PublishAlignment();
  PublishTrack();
}

}  // namespace floorpose::platform
