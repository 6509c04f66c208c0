#include "tools/lib/evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "core/sim/simulator.h"
#include "platform/clock.h"
#include "platform/codec.h"
#include "platform/engine.h"
#include "platform/recording.h"
#include "tools/lib/simulate_recording.h"

#include <spdlog/spdlog.h>

namespace floorpose::tools {
namespace {

using platform::Topic;

struct Input {
  int64_t stamp_ns;
  Topic topic;
  platform::Envelope envelope;
};

// What a recording gives an evaluation: the daemon's inputs in the daemon's order, the
// ground truth by stamp, and the headset's device id.
struct Recorded {
  std::vector<Input> inputs;
  std::map<int64_t, v1::GroundTruthPose> truth;
  std::string device_id;
};

bool ReadRecorded(const std::string& recording, EvalReport* report, Recorded* out,
                  std::string* error) {
  platform::RecordingReader reader(recording);
  if (!reader.ok()) {
    *error = reader.error();
    return false;
  }
  v1::RecordingRecord record;
  while (reader.Next(&record)) {
    if (record.topic() == kSimInfoTopic) {
      v1::SimulationInfo info;
      if (info.ParseFromString(record.envelope().payload())) {
        report->scenario = info.scenario();
        report->seed = info.seed();
        report->plan_id = info.plan_id();
      }
      continue;
    }
    if (record.topic() == kGroundTruthTopic) {
      v1::GroundTruthPose gt;
      if (gt.ParseFromString(record.envelope().payload())) out->truth[gt.stamp_ns()] = gt;
      continue;
    }
    const auto topic = platform::TopicFromName(record.topic());
    if (!topic ||
        (*topic != Topic::kMeshDelta && *topic != Topic::kHeadsetPose && *topic != Topic::kCommand))
      continue;  // daemon outputs in a recording of a live session
    if (out->device_id.empty() && *topic == Topic::kHeadsetPose)
      out->device_id = record.envelope().device_id();
    out->inputs.push_back(
        {record.envelope().stamp_ns(), *topic, platform::FromProto(record.envelope())});
  }
  if (!reader.error().empty()) {
    *error = recording + ": " + reader.error();
    return false;
  }
  if (out->truth.empty()) {
    *error = recording + ": no ground truth in the recording (made by `floorpose simulate`?)";
    return false;
  }
  // The daemon's order (it sorts each batch the same way).
  std::stable_sort(out->inputs.begin(), out->inputs.end(), [](const Input& a, const Input& b) {
    return platform::InputBefore(a.topic, a.stamp_ns, b.topic, b.stamp_ns);
  });
  return true;
}

// The newest pose with ground truth, as the replay goes.
struct Latest {
  Eigen::Vector2d slam, plan;
  int64_t stamp_ns;
  Se2 T_plan_slam;  // the true alignment at this pose
  // How far an alignment puts this pose's wearer from the truth, metres.
  double OffAtWearer(const Se2& T) const { return (T * slam - plan).norm(); }
};

// For tuning (--log-level debug): how a job's result, and the alignment in use, put the
// wearer against the truth; the engine logs its decision right after.
void LogAgainstTruth(const platform::Done& done, const Latest& latest,
                     const platform::Engine& engine, const v1::FloorposedConfig& config,
                     int64_t start_ns) {
  const double at_s = static_cast<double>(latest.stamp_ns - start_ns) * 1e-9;
  if (done.job.global && done.job.index) {
    // The true place as a search would have it: is it missed, or beaten?
    const double score = done.job.global->Get().Score(done.job.cloud, latest.T_plan_slam);
    const std::vector<GlobalPlace> true_place =
        platform::RefineAsSearch(done.job, {{latest.T_plan_slam, score}});
    for (const GlobalPlace& place : true_place)
      spdlog::debug(
          "truth itself: scoring {:.3f}, refined fit {:.4f}, {:.0f}% inliers, {} crossings, "
          "{:.0f}% hidden, {:.0f}% unseen of {}, {:.2f} m from the truth",
          place.score, place.fit_mse, 100 * place.inlier_ratio, place.path_crossings,
          100 * place.hidden_ratio, 100 * place.unseen_ratio, place.unseen_expected,
          latest.OffAtWearer(place.T_plan_slam));
  }
  if (done.job.global) {
    for (const GlobalPlace& place : done.places)
      spdlog::debug(
          "at {:.1f} s, truth: place scoring {:.3f} (fit {:.4f}, {:.0f}% inliers, {} "
          "crossings, {:.0f}% hidden, {:.0f}% unseen of {}, {:.0f}% alike, rank {}) is {:.2f} "
          "m off at the wearer; T {:.3f} {:.3f} {:.4f}, wearer {:.2f} {:.2f} (slam)",
          at_s, place.score, place.fit_mse, 100 * place.inlier_ratio, place.path_crossings,
          100 * place.hidden_ratio, 100 * place.unseen_ratio, place.unseen_expected,
          100 * place.alike, place.rank, latest.OffAtWearer(place.T_plan_slam),
          place.T_plan_slam.t.x(), place.T_plan_slam.t.y(), place.T_plan_slam.theta,
          latest.slam.x(), latest.slam.y());
    return;
  }
  if (!done.job.index) return;
  // What share of the registered walls lies on the plan under each: low under the truth
  // too means the plan lacks what the wearer sees, not a wrong result.
  const std::vector<Eigen::Vector2d>& cloud = done.job.cloud;
  const auto on_plan = [&](const Se2& T) {
    RegistrationResult fit;
    EvaluateFit(cloud, *done.job.index, T, config.icp().max_correspondence_m(),
                config.icp().inlier_threshold_m(), &fit, nullptr);
    return 100.0 * fit.inliers / std::max<size_t>(1, cloud.size());
  };
  const Se2& in_use = engine.tracker().alignment().T_plan_slam;
  // The belief's mass at the truth: a minority place that is right, or none at all.
  const double at_truth =
      done.mcl ? done.mcl->belief.MassWithin(latest.slam, latest.plan,
                                             engine.tracker().options().publish.within_m)
               : 0.0;
  spdlog::debug(
      "at {:.1f} s, truth: result {:.2f} m off at the wearer, alignment in use {:.2f} m; "
      "on the plan: {:.0f}% under the result, {:.0f}% in use, {:.0f}% true; the result "
      "turns {:.1f} deg from the truth, the alignment in use {:.1f}; the belief holds "
      "{:.0f}% within 1 m of the truth",
      at_s, latest.OffAtWearer(done.result.T_plan_slam), latest.OffAtWearer(in_use),
      on_plan(done.result.T_plan_slam), on_plan(in_use), on_plan(latest.T_plan_slam),
      WrapAngle(done.result.T_plan_slam.theta - latest.T_plan_slam.theta) * 180 / M_PI,
      WrapAngle(in_use.theta - latest.T_plan_slam.theta) * 180 / M_PI, 100 * at_truth);
}

// What a replay learns beside the poses the engine publishes.
struct Replay {
  std::map<int64_t, Pose2> slam_poses;  // for the best-fit baseline
  std::set<int64_t> registered;         // poses published under a registered alignment
  std::vector<double> reg_times;
  std::vector<int64_t> resumed;  // losses of tracking, as the tracker takes them: the
                                 // stamp of the first pose after each
  std::optional<Latest> latest;
  std::optional<int64_t> last_pose_ns;
  bool said_lost = false;

  // A headset pose as the engine took it: a loss of tracking ended (TRACKING_LOST, or a
  // silence of more than lost_after_ns), and the truth at it.
  void Observe(const platform::DecodedPose& pose,
               const std::map<int64_t, v1::GroundTruthPose>& truth, int64_t lost_after_ns,
               bool keep_slam) {
    if (pose.tracking == v1::HeadsetPose::TRACKING_LOST) {
      said_lost = true;
    } else {
      if (last_pose_ns && (said_lost || pose.stamp_ns - *last_pose_ns > lost_after_ns))
        resumed.push_back(pose.stamp_ns);
      said_lost = false;
    }
    last_pose_ns = pose.stamp_ns;
    if (keep_slam) slam_poses[pose.stamp_ns] = pose.pose_slam;
    if (auto it = truth.find(pose.stamp_ns); it != truth.end())
      latest = Latest{pose.pose_slam.position,
                      {it->second.x(), it->second.y()},
                      pose.stamp_ns,
                      Se2{it->second.heading(), {it->second.x(), it->second.y()}} *
                          Se2{pose.pose_slam.heading, pose.pose_slam.position}.Inverse()};
  }
};

// Feeds every input to the engine on its virtual clock, and runs every job it asks for at
// once (the worker, without its wait), so that a replay is deterministic.
Replay ReplayInputs(const Recorded& rec, const v1::FloorposedConfig& config, Baseline baseline,
                    bool no_pick, platform::RecordingWriter* session, int64_t* virtual_now,
                    platform::Engine& engine, EvalReport* report) {
  Replay out;
  const HeadsetFrame frame =
      ParseHeadsetFrame(config.headset_frame()).value_or(HeadsetFrame::kUnityLeftHandedYUp);
  const auto lost_after_ns = static_cast<int64_t>(config.tracking().motion().lost_after_s() * 1e9);
  const int64_t start_ns = rec.inputs.front().stamp_ns;
  for (const Input& in : rec.inputs) {
    *virtual_now = in.stamp_ns;
    if (session) session->Append(*virtual_now, in.topic, in.envelope);
    switch (in.topic) {
      case Topic::kCommand: {
        v1::Command command;
        if (no_pick && command.ParseFromString(in.envelope.payload) &&
            command.command_case() == v1::Command::kWallPick)
          break;
        engine.OnCommand(in.envelope);
        break;
      }
      case Topic::kMeshDelta: engine.OnMeshDelta(in.envelope); break;
      case Topic::kHeadsetPose: {
        const size_t published = report->plan_poses.size();
        engine.OnHeadsetPose(in.envelope);
        if (report->plan_poses.size() > published &&
            engine.tracker().alignment().source == AlignmentSource::kRegistration)
          out.registered.insert(report->plan_poses.back().source_stamp_ns());
        platform::DecodedPose pose;
        if (platform::DecodeHeadsetPose(in.envelope.payload, frame, config.limits(), &pose).empty())
          out.Observe(pose, rec.truth, lost_after_ns, baseline == Baseline::kBestFit);
        break;
      }
      default: break;
    }
    if (baseline != Baseline::kNone) continue;  // baselines never register
    auto job = engine.TakeDueJob();
    if (!job) continue;
    platform::Done done = platform::RunJob(std::move(*job), platform::MonotonicNs);
    if (!done.job.global) {
      out.reg_times.push_back(done.result.time_ms);
    } else if (report->global_searches++ == 0) {
      report->first_search_s = static_cast<double>(done.job.stamp_ns - start_ns) * 1e-9;
      for (size_t i = 0; out.latest && i < done.places.size(); ++i)
        if (out.latest->OffAtWearer(done.places[i].T_plan_slam) <= 1.0) {
          report->first_search_truth = static_cast<int>(i);
          break;
        }
    }
    if (out.latest && spdlog::should_log(spdlog::level::debug))
      LogAgainstTruth(done, *out.latest, engine, config, start_ns);
    engine.OnRegistrationDone(std::move(done));
  }
  return out;
}

// Every published plan pose that has ground truth, scored into report->track; poses before
// the first alignment only counted. With a best-fit baseline, the fit's position instead.
void ScorePoses(const std::map<int64_t, v1::GroundTruthPose>& truth, const Replay& replay,
                const std::optional<Se2>& best_fit, EvalReport* report) {
  const std::vector<v1::PlanPose>& plan_poses = report->plan_poses;
  std::optional<Eigen::Vector2d> first_true;  // of the first published pose with a truth
  for (const v1::PlanPose& p : plan_poses) {
    auto it = truth.find(p.source_stamp_ns());
    if (it == truth.end()) continue;
    // The wearer's first step, timed as time_to_first_reliable_s is: from the first pose
    // published, placed or not.
    const Eigen::Vector2d true_xy(it->second.x(), it->second.y());
    if (!first_true) first_true = true_xy;
    if (report->first_step_s < 0 && (true_xy - *first_true).norm() >= kFirstStepM)
      report->first_step_s =
          static_cast<double>(p.source_stamp_ns() - plan_poses.front().source_stamp_ns()) * 1e-9;
    // Before the first alignment the daemon has no plan position to give (it says so:
    // version 0, UNRELIABLE); the thesis scores from the initial alignment on.
    // A building of several floors: on the truth's floor or not (before any alignment too).
    if (!it->second.floor().empty() && p.floor() != it->second.floor()) ++report->wrong_floor_poses;
    if (p.alignment_version() == 0 && !best_fit) {
      ++report->unaligned_poses;
      continue;
    }
    EvalPose e;
    e.stamp_ns = p.source_stamp_ns();
    e.x = p.x();
    e.y = p.y();
    e.heading = p.heading();
    e.alignment_version = p.alignment_version();
    e.registered = replay.registered.count(e.stamp_ns) > 0;
    e.reliable = p.reliability().flag() == v1::Reliability::RELIABLE;
    e.unreliable = p.reliability().flag() == v1::Reliability::UNRELIABLE;
    e.probability = p.reliability().probability();
    e.reason = p.reliability().reason();
    if (best_fit) {
      const auto s = replay.slam_poses.find(e.stamp_ns);
      if (s == replay.slam_poses.end()) continue;
      const Eigen::Vector2d q = *best_fit * s->second.position;
      e.x = q.x();
      e.y = q.y();
      e.reliable = false;  // an after-the-fact fit flags nothing
    }
    e.true_x = it->second.x();
    e.true_y = it->second.y();
    e.marker = it->second.marker();
    e.error_m = std::hypot(e.x - e.true_x, e.y - e.true_y);
    if (e.reliable && report->time_to_first_reliable_s < 0) {
      report->time_to_first_reliable_s =
          static_cast<double>(e.stamp_ns - plan_poses.front().source_stamp_ns()) * 1e-9;
      report->first_reliable_error_m = e.error_m;
    }
    report->track.push_back(e);
  }
}

// The report's figures from its scored track.
void Summarize(const std::vector<int64_t>& resumed, bool best_fit, EvalReport* report) {
  const std::vector<EvalPose>& t = report->track;
  std::vector<double> errors, marker_errors;
  size_t reliable = 0, reliable_ok = 0;
  double brier = 0;
  for (const EvalPose& e : t) {
    errors.push_back(e.error_m);
    if (e.marker) marker_errors.push_back(e.error_m);
    reliable += e.reliable;
    reliable_ok += e.reliable && e.error_m <= 1.0;
    const double miss = e.probability - (e.error_m <= 1.0 ? 1.0 : 0.0);
    brier += miss * miss;
  }
  report->poses = errors.size();
  if (!marker_errors.empty()) report->marker_mean_error_m = Mean(marker_errors);
  if (errors.empty()) return;
  report->mean_error_m = Mean(errors);
  report->p95_error_m = Percentile(errors, 0.95);
  report->max_error_m = *std::max_element(errors.begin(), errors.end());
  report->final_error_m = errors.back();
  report->divergences = static_cast<size_t>(
      std::count_if(errors.begin(), errors.end(), [](double x) { return x > 5.0; }));
  report->reliable_fraction = static_cast<double>(reliable) / static_cast<double>(errors.size());
  report->reliable_precision_1m =
      reliable ? static_cast<double>(reliable_ok) / static_cast<double>(reliable) : 0.0;
  report->false_reliable_poses = reliable - reliable_ok;
  report->brier = brier / static_cast<double>(errors.size());
  const auto since_first = [&](auto it) {
    return it == t.end() ? -1.0 : static_cast<double>(it->stamp_ns - t.front().stamp_ns) * 1e-9;
  };
  report->time_to_unreliable_s =
      since_first(std::find_if(t.begin(), t.end(), [](const EvalPose& p) { return p.unreliable; }));
  const auto recovered = std::find_if(
      t.begin(), t.end(), [](const EvalPose& p) { return p.reliable && p.error_m <= 1.0; });
  report->time_to_recovered_s = since_first(recovered);
  report->false_reliable_before_recovered = static_cast<size_t>(std::count_if(
      t.begin(), recovered, [](const EvalPose& p) { return p.reliable && p.error_m > 1.0; }));
  report->losses = ScoreLosses(t, resumed);
  report->pick_error_m = t.front().error_m;
  // The first pose under a registered alignment (turning the pick onto the walls'
  // directions changes the version too, but is not a registration).
  const auto fix = std::find_if(t.begin(), t.end(), [](const EvalPose& p) { return p.registered; });
  if (!best_fit && fix != t.end()) {
    report->first_fix_s = static_cast<double>(fix->stamp_ns - t.front().stamp_ns) * 1e-9;
    double settled = 0;
    for (auto p = fix; p != t.end(); ++p) {
      settled += p->error_m;
      report->settled_max_error_m = std::max(report->settled_max_error_m, p->error_m);
    }
    report->settled_mean_error_m = settled / static_cast<double>(t.end() - fix);
  }
}

// One SE(2) fitted after the fact to the whole walk's SLAM poses and their truth.
Se2 BestFit(const std::map<int64_t, Pose2>& slam_poses,
            const std::map<int64_t, v1::GroundTruthPose>& truth) {
  std::vector<Eigen::Vector2d> from, to;
  for (const auto& [stamp, pose] : slam_poses) {
    auto it = truth.find(stamp);
    if (it == truth.end()) continue;
    from.push_back(pose.position);
    to.emplace_back(it->second.x(), it->second.y());
  }
  return sim::FitSe2(from, to);
}

}  // namespace

double Mean(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1,
                    static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5))];
}

bool Evaluate(const v1::FloorposedConfig& base_config, const std::string& recording,
              Baseline baseline, EvalReport* report, std::string* error,
              platform::RecordingWriter* session, bool no_pick) {
  *report = {};
  Recorded rec;
  if (!ReadRecorded(recording, report, &rec, error)) return false;
  v1::FloorposedConfig config = base_config;
  if (!rec.device_id.empty()) config.mutable_dds()->set_device_id(rec.device_id);
  report->method = baseline == Baseline::kNoAlgorithm ? "none"
                   : baseline == Baseline::kBestFit   ? "best-fit"
                                                      : "mcl";
  int64_t virtual_now = 0;
  uint64_t session_seq = 0;
  platform::Engine engine(
      config,
      [&](Topic t, const google::protobuf::Message& m) {
        if (session)
          session->Append(
              virtual_now, t,
              {config.dds().device_id(), ++session_seq, virtual_now, m.SerializeAsString()});
        if (t == Topic::kPlanPose)
          report->plan_poses.push_back(static_cast<const v1::PlanPose&>(m));
        if (t == Topic::kExplored) report->explored = static_cast<const v1::ExploredMap&>(m);
        if (t == Topic::kPlanTrack) {
          ++report->plan_tracks;
          report->last_plan_track = static_cast<const v1::PlanTrack&>(m);
        }
      },
      [&] { return virtual_now; });
  if (const std::string e = engine.Start(); !e.empty()) {
    *error = e;
    return false;
  }
  const Replay replay =
      ReplayInputs(rec, config, baseline, no_pick, session, &virtual_now, engine, report);
  engine.PublishExplored();  // what was explored since the last one
  report->floor_changes = engine.counters().floor_changes();
  std::optional<Se2> best_fit;
  if (baseline == Baseline::kBestFit) best_fit = BestFit(replay.slam_poses, rec.truth);
  ScorePoses(rec.truth, replay, best_fit, report);
  Summarize(replay.resumed, best_fit.has_value(), report);
  report->registrations = engine.counters().registrations();
  report->accepted = engine.counters().registrations_accepted();
  report->reg_time_ms_median = Percentile(replay.reg_times, 0.5);
  report->reg_time_ms_max = replay.reg_times.empty() ? 0.0
                                                     : *std::max_element(replay.reg_times.begin(),
                                                                         replay.reg_times.end());
  return true;
}

std::vector<LossScore> ScoreLosses(const std::vector<EvalPose>& track,
                                   const std::vector<int64_t>& resumed) {
  std::vector<LossScore> out;
  if (track.empty()) return out;
  const auto seconds = [](int64_t ns) { return static_cast<double>(ns) * 1e-9; };
  for (size_t k = 0; k < resumed.size(); ++k) {
    const int64_t from = resumed[k];
    const int64_t to = k + 1 < resumed.size() ? resumed[k + 1] : INT64_MAX;
    LossScore loss;
    loss.resumed_s = seconds(from - track.front().stamp_ns);
    for (const EvalPose& p : track) {
      if (p.stamp_ns < from || p.stamp_ns >= to) continue;
      loss.followed_s = seconds(p.stamp_ns - from);
      if (loss.back_s >= 0 || !p.reliable) continue;
      if (p.error_m <= 1.0)
        loss.back_s = seconds(p.stamp_ns - from);
      else
        ++loss.false_reliable;
    }
    out.push_back(loss);
  }
  return out;
}

const char* SimulatedSplit(uint64_t seed) { return seed >= 11 ? "development" : "validation"; }

const char* CarmenSplit(const std::string& log) {
  for (const char* dev : {"aces", "csail", "freiburg-101", "orebro"})
    if (log == dev) return "development";
  return "validation";
}

const char* IlcSplit(const std::string& floor) {
  for (const char* dev : {"B1", "F1", "F2"})
    if (floor == dev) return "development";
  return "validation";
}

LossCounts CountLosses(const std::vector<LossScore>& losses) {
  LossCounts c;
  for (const LossScore& l : losses) {
    c.timed += l.timed();
    c.back += l.back_in_time();
    c.false_reliable += l.false_reliable;
  }
  return c;
}

std::string ToJson(const EvalReport& r) {
  // Through the library, so that any plan name is valid JSON and a NaN is null.
  const LossCounts losses = CountLosses(r.losses);
  const nlohmann::ordered_json j = {
      {"method", r.method},
      {"scenario", r.scenario},
      {"plan", r.plan_id},
      {"seed", r.seed},
      {"split", r.split},
      {"cpu_s", r.cpu_s},
      {"mean_error_m", r.mean_error_m},
      {"p95_error_m", r.p95_error_m},
      {"max_error_m", r.max_error_m},
      {"final_error_m", r.final_error_m},
      {"marker_mean_error_m", r.marker_mean_error_m},
      {"divergences", r.divergences},
      {"pick_error_m", r.pick_error_m},
      {"first_fix_s", r.first_fix_s},
      {"settled_mean_error_m", r.settled_mean_error_m},
      {"settled_max_error_m", r.settled_max_error_m},
      {"registrations", r.registrations},
      {"accepted", r.accepted},
      {"reg_time_ms_median", r.reg_time_ms_median},
      {"reg_time_ms_max", r.reg_time_ms_max},
      {"reliable_fraction", r.reliable_fraction},
      {"reliable_precision_1m", r.reliable_precision_1m},
      {"brier", r.brier},
      {"poses", r.poses},
      {"unaligned_poses", r.unaligned_poses},
      {"time_to_first_reliable_s", r.time_to_first_reliable_s},
      {"first_reliable_error_m", r.first_reliable_error_m},
      {"false_reliable_poses", r.false_reliable_poses},
      {"time_to_unreliable_s", r.time_to_unreliable_s},
      {"time_to_recovered_s", r.time_to_recovered_s},
      {"first_step_s", r.first_step_s},
      {"false_reliable_before_recovered", r.false_reliable_before_recovered},
      {"losses", r.losses.size()},
      {"losses_timed", losses.timed},
      {"losses_back_in_time", losses.back},
      {"false_reliable_after_losses", losses.false_reliable},
      {"global_searches", r.global_searches},
      {"first_search_s", r.first_search_s},
      {"first_search_truth", r.first_search_truth},
      {"wrong_floor_poses", r.wrong_floor_poses},
      {"floor_changes", r.floor_changes}};
  return j.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

std::string ToText(const EvalReport& r) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(3);
  s << "method " << r.method << ", plan " << r.plan_id << ", scenario " << r.scenario << ", seed "
    << r.seed << ", " << r.poses << " poses scored (" << r.unaligned_poses
    << " before the first alignment not)\n"
    << "  error mean / p95 / max        " << r.mean_error_m << " / " << r.p95_error_m << " / "
    << r.max_error_m << " m\n"
    << "  final error                   " << r.final_error_m << " m\n"
    << "  mean error at the markers     " << r.marker_mean_error_m << " m\n"
    << "  divergences (> 5 m)           " << r.divergences << " poses\n"
    << "  the pick's own error          " << r.pick_error_m << " m\n"
    << "  first registered pose after   " << r.first_fix_s << " s (-1: none)\n"
    << "  error mean / max since        " << r.settled_mean_error_m << " / "
    << r.settled_max_error_m << " m\n"
    << "  registrations run / accepted  " << r.registrations << " / " << r.accepted << "\n"
    << "  registration time median/max  " << r.reg_time_ms_median << " / " << r.reg_time_ms_max
    << " ms\n"
    << "  flagged reliable              " << 100 * r.reliable_fraction << "% of poses, "
    << 100 * r.reliable_precision_1m << "% of those within 1 m\n"
    << "  Brier score (probability)     " << r.brier << "\n"
    << "  first reliable pose after     " << r.time_to_first_reliable_s << " s (-1: none)\n"
    << "  reliable but over 1 m off     " << r.false_reliable_poses << " poses\n"
    << "  first unreliable pose after   " << r.time_to_unreliable_s << " s (-1: none)\n"
    << "  first reliable within 1 m     " << r.time_to_recovered_s << " s (-1: none)\n"
    << "  ...and before it              " << r.false_reliable_before_recovered
    << " poses reliable but over 1 m off\n";
  for (const LossScore& l : r.losses)
    s << "  loss of tracking, resumed at " << l.resumed_s << " s: reliable within 1 m " << l.back_s
      << " s later (-1: not in the " << l.followed_s << " s followed), " << l.false_reliable
      << " poses reliable but over 1 m off before\n";
  if (r.global_searches)
    s << "  whole-plan searches           " << r.global_searches << ", the first at "
      << r.first_search_s << " s, the truth its place " << r.first_search_truth
      << " (0: first, -1: none)\n";
  if (r.floor_changes || r.wrong_floor_poses)
    s << "  floor changes                 " << r.floor_changes << ", " << r.wrong_floor_poses
      << " poses on another floor than the truth's\n";
  return s.str();
}

std::string ToTrackCsv(const EvalReport& r) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(3);
  s << "t_s,x,y,true_x,true_y,error_m,reliable,probability,alignment_version,reason\n";
  const int64_t t0 = r.track.empty() ? 0 : r.track.front().stamp_ns;
  for (const EvalPose& p : r.track)
    s << static_cast<double>(p.stamp_ns - t0) * 1e-9 << "," << p.x << "," << p.y << "," << p.true_x
      << "," << p.true_y << "," << p.error_m << "," << p.reliable << "," << p.probability << ","
      << p.alignment_version << ",\"" << p.reason << "\"\n";
  return s.str();
}

namespace {

// Okabe and Ito's colours: told apart with any colour vision.
constexpr const char* kReliableColour = "#0072B2";  // blue
constexpr const char* kOtherColour = "#E69F00";     // orange
constexpr const char* kTruthColour = "#000000";

std::string XmlText(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '&')
      out += "&amp;";
    else if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else
      out += c;
  }
  return out;
}

// A round length (1, 2 or 5 times a power of ten) near a fifth of `span`.
double ScaleBarLength(double span) {
  const double target = std::max(span / 5, 1e-3);
  const double power = std::pow(10.0, std::floor(std::log10(target)));
  for (double f : {5.0, 2.0, 1.0})
    if (f * power <= target) return f * power;
  return power;
}

std::string BarLabel(double metres) {
  char text[32];
  std::snprintf(text, sizeof text, "%g m", metres);
  return text;
}

// Plan metres to SVG pixels: y up on the plan, down in SVG, `margin` metres about the plan
// and both tracks.
struct SvgMap {
  static constexpr double kScale = 20.0;  // pixels a metre
  Eigen::Vector2d lo, hi;
  double X(double x) const { return (x - lo.x()) * kScale; }
  double Y(double y) const { return (hi.y() - y) * kScale; }
  double width() const { return (hi.x() - lo.x()) * kScale; }
  double height() const { return (hi.y() - lo.y()) * kScale; }
};

SvgMap MapOf(const FloorPlan& plan, const EvalReport& r, double margin) {
  SvgMap m{plan.min, plan.max};
  for (const EvalPose& p : r.track) {
    m.lo = m.lo.cwiseMin(Eigen::Vector2d(p.x, p.y)).cwiseMin(Eigen::Vector2d(p.true_x, p.true_y));
    m.hi = m.hi.cwiseMax(Eigen::Vector2d(p.x, p.y)).cwiseMax(Eigen::Vector2d(p.true_x, p.true_y));
  }
  m.lo -= Eigen::Vector2d::Constant(margin);
  m.hi += Eigen::Vector2d::Constant(margin);
  return m;
}

// The plan's walls as one path, to a tenth of a pixel (5 mm): a raster plan has tens of
// thousands of segments. The truth thin and dashed; the estimate in runs of one colour,
// blue while RELIABLE, orange while not.
void SvgWallsAndTracks(std::ostringstream& s, const FloorPlan& plan, const EvalReport& r,
                       const SvgMap& m) {
  s << "<path fill=\"none\" stroke=\"#555\" stroke-width=\"2\" d=\"";
  s.precision(1);
  for (const Segment& seg : plan.segments)
    s << "M" << m.X(seg.a.x()) << " " << m.Y(seg.a.y()) << "L" << m.X(seg.b.x()) << " "
      << m.Y(seg.b.y());
  s << "\"/>\n";
  s << "<polyline fill=\"none\" stroke=\"" << kTruthColour
    << "\" stroke-width=\"1.5\" stroke-dasharray=\"6 4\" points=\"";
  for (const EvalPose& p : r.track) s << m.X(p.true_x) << "," << m.Y(p.true_y) << " ";
  s << "\"/>\n";
  for (size_t i = 1; i < r.track.size();) {
    const bool reliable = r.track[i].reliable;
    s << "<polyline fill=\"none\" stroke-width=\"2.5\" stroke=\""
      << (reliable ? kReliableColour : kOtherColour) << "\" points=\"" << m.X(r.track[i - 1].x)
      << "," << m.Y(r.track[i - 1].y);
    for (; i < r.track.size() && r.track[i].reliable == reliable; ++i)
      s << " " << m.X(r.track[i].x) << "," << m.Y(r.track[i].y);
    s << "\"/>\n";
  }
  s.precision(2);
}

// The markers, the truth's and the estimate's; a scale bar in metres, bottom left; the
// legend.
void SvgMarkersAndLegend(std::ostringstream& s, const EvalReport& r, const SvgMap& m) {
  for (const EvalPose& p : r.track) {
    if (!p.marker) continue;
    s << "<circle cx=\"" << m.X(p.true_x) << "\" cy=\"" << m.Y(p.true_y)
      << "\" r=\"4\" fill=\"none\" stroke=\"" << kTruthColour << "\" stroke-width=\"1.5\"/>"
      << "<circle cx=\"" << m.X(p.x) << "\" cy=\"" << m.Y(p.y) << "\" r=\"4\" fill=\""
      << (p.reliable ? kReliableColour : kOtherColour) << "\"/><text x=\"" << m.X(p.true_x) + 6
      << "\" y=\"" << m.Y(p.true_y) - 6 << "\" font-size=\"13\">" << p.marker << "</text>\n";
  }
  const double bar = ScaleBarLength(m.hi.x() - m.lo.x());
  const double map_h = m.height(), bar_px = bar * SvgMap::kScale;
  s << "<path d=\"M10 " << map_h - 12 << "h" << bar_px << "M10 " << map_h - 17 << "v10M"
    << 10 + bar_px << " " << map_h - 17 << "v10\" stroke=\"black\" stroke-width=\"2\"/>"
    << "<text x=\"" << 14 + bar_px << "\" y=\"" << map_h - 8 << "\" font-size=\"13\">"
    << BarLabel(bar) << "</text>\n";
  s << "<text x=\"10\" y=\"20\" font-size=\"15\">" << XmlText(r.method) << " (mean "
    << r.mean_error_m << " m): <tspan fill=\"" << kReliableColour << "\">RELIABLE</tspan>, "
    << "<tspan fill=\"" << kOtherColour << "\">not RELIABLE</tspan>; truth dashed</text>\n";
}

// Error over time, from x0, plot_w wide: the same colours, a line at 1 m.
void SvgErrorPlot(std::ostringstream& s, const EvalReport& r, double x0, double plot_w,
                  double height) {
  if (r.track.empty()) return;
  const double top = 30, bottom = height - 30, left = x0 + 40;
  const double t0 = static_cast<double>(r.track.front().stamp_ns) * 1e-9;
  const double t1 = std::max(t0 + 1, static_cast<double>(r.track.back().stamp_ns) * 1e-9);
  double emax = 2.0;
  for (const EvalPose& p : r.track) emax = std::max(emax, std::min(p.error_m, 20.0));
  auto PX = [&](int64_t ns) {
    return left + (static_cast<double>(ns) * 1e-9 - t0) / (t1 - t0) * (plot_w - 50);
  };
  auto PY = [&](double e) { return bottom - std::min(e, emax) / emax * (bottom - top); };
  s << "<text x=\"" << left << "\" y=\"20\" font-size=\"15\">error (m) over " << t1 - t0
    << " s</text>\n"
    << "<path d=\"M" << left << " " << top << "V" << bottom << "H" << left + plot_w - 50
    << "\" fill=\"none\" stroke=\"black\"/>\n"
    << "<path d=\"M" << left << " " << PY(1.0) << "H" << left + plot_w - 50
    << "\" stroke=\"#999\" stroke-dasharray=\"4 3\"/><text x=\"" << left - 30 << "\" y=\""
    << PY(1.0) + 4 << "\" font-size=\"12\">1 m</text><text x=\"" << left - 36 << "\" y=\""
    << top + 4 << "\" font-size=\"12\">" << emax << "</text>\n";
  s.precision(1);
  for (const bool reliable : {false, true}) {
    s << "<path fill=\"" << (reliable ? kReliableColour : kOtherColour) << "\" d=\"";
    for (const EvalPose& p : r.track)
      if (p.reliable == reliable)
        s << "M" << PX(p.stamp_ns) << " " << PY(p.error_m) << "h1.5v1.5h-1.5z";
    s << "\"/>\n";
  }
}

}  // namespace

std::string ToSvg(const FloorPlan& plan, const EvalReport& r) {
  // The plan and the tracks; the error plot to the right.
  const double plot_w = 420, gap = 30;
  const SvgMap map = MapOf(plan, r, 2.0);
  const double height = std::max(map.height(), 260.0), width = map.width() + gap + plot_w;
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(2);
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
    << "\" font-family=\"sans-serif\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<title>" << XmlText(r.plan_id) << " " << XmlText(r.scenario) << " seed " << r.seed << " "
    << XmlText(r.method) << ": mean " << r.mean_error_m << " m, max " << r.max_error_m
    << " m</title>\n";
  SvgWallsAndTracks(s, plan, r, map);
  SvgMarkersAndLegend(s, r, map);
  SvgErrorPlot(s, r, map.width() + gap, plot_w, height);
  s << "</svg>\n";
  return s.str();
}

}  // namespace floorpose::tools
