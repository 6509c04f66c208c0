// Engine's side of the worker's jobs (platform/jobs.h): taking the one due, and what its
// result changes.
#include <spdlog/spdlog.h>

#include "platform/engine.h"

namespace floorpose::platform {

std::optional<Job> Engine::TakeDueJob() {
  return jobs_.TakeDue(tracker_, store_, plans_.current().global,
                       config().walls().window_max_points(), intake_.clock().newest_ns());
}

void Engine::OnRegistrationDone(Done done) {
  jobs_.Finished(done);
  if (done.job.global) {
    const std::string what = tracker_.OfferPlaces(done.places, done.job.cloud, done.job.stamp_ns);
    spdlog::info("global search: {} points, {} place(s), {:.1f} ms: {}", done.job.cloud.size(),
                 done.places.size(), done.result.time_ms, what);
    PublishAlignment();
    return;
  }
  if (!done.mcl) return;
  intake_.counters().set_registrations(intake_.counters().registrations() + 1);
  const size_t samples = done.mcl->belief.size(), places = done.mcl->places;
  const double fit = done.mcl->fit;
  const bool polished = done.mcl->polished, offered = done.mcl->offered;
  const bool taken = tracker_.FinishUpdate(std::move(*done.mcl), done.job.stamp_ns);
  const Reliability r = tracker_.CurrentReliability();
  jobs_.SetLast({done.result, taken, taken ? r.reason : "a new prior came meanwhile"});
  spdlog::info("belief: {} samples, {} place(s), fit {:.2f}, polished {}, {:.1f} ms: {:.0f}% {}{}",
               samples, places, fit, polished, done.result.time_ms, 100 * r.probability, r.reason,
               offered ? " (offered the place ICP reached)" : "");
  if (!taken) return;
  intake_.counters().set_registrations_accepted(intake_.counters().registrations_accepted() + 1);
  PublishAlignment();
  PublishTrack();
}

}  // namespace floorpose::platform
