// `floorpose eval`: a recording through the daemon's own code on a virtual clock, scored
// against its ground truth with the thesis' metrics.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <fstream>
#include <optional>

#include "platform/config.h"
#include "platform/floor_plan_io.h"
#include "tools/floorpose/commands.h"
#include "tools/lib/evaluation.h"

namespace floorpose::tools {
namespace {

struct EvalOptions {
  std::string plan, recording, baseline, config, svg, track, session;
  bool json = false;
  bool no_pick = false;
};

int RunEval(const EvalOptions& o) {
  // The report is the output, not the daemon's log (`floorpose --log-level debug eval` shows it).
  if (spdlog::get_level() > spdlog::level::debug) spdlog::set_level(spdlog::level::warn);
  v1::FloorposedConfig config;
  std::string error;
  if (!platform::LoadConfig(o.config, &config, &error)) {
    spdlog::error("{}", error);
    return 2;
  }
  config.set_plan_path(o.plan);
  config.set_log_level("warn");
  if (const std::string e = platform::ValidateConfig(config); !e.empty()) {
    spdlog::error("{}", e);
    return 2;
  }
  const Baseline baseline = o.baseline == "best-fit" ? Baseline::kBestFit
                            : o.baseline == "none"   ? Baseline::kNoAlgorithm
                                                     : Baseline::kNone;
  std::optional<platform::RecordingWriter> session;
  if (!o.session.empty()) {
    session.emplace(o.session);
    if (!session->ok()) {
      spdlog::error("{}", session->error());
      return 1;
    }
  }
  EvalReport report;
  if (!Evaluate(config, o.recording, baseline, &report, &error, session ? &*session : nullptr,
                o.no_pick)) {
    spdlog::error("{}", error);
    return 1;
  }
  if (session && (!session->Flush() || !session->ok())) {
    spdlog::error("{}: {}", o.session, session->error());
    return 1;
  }
  if (!o.svg.empty()) {
    const FloorPlanParse plan = platform::LoadFloorPlan(o.plan);
    std::ofstream(o.svg) << ToSvg(plan.plan, report);
  }
  if (!o.track.empty()) std::ofstream(o.track) << ToTrackCsv(report);
  std::fputs((o.json ? ToJson(report) + "\n" : ToText(report)).c_str(), stdout);
  return 0;
}

}  // namespace

Run AddEvalCommand(CLI::App& app) {
  auto o = std::make_shared<EvalOptions>();
  app.add_option("--plan", o->plan, "floor plan (.geojson or .txt)")->required();
  app.add_option("--recording", o->recording, "recording made by `floorpose simulate`")->required();
  app.add_option("--baseline", o->baseline,
                 "instead of registering: none (the wall pick only, the thesis' \"no "
                 "algorithm\") or best-fit (one SE(2) fitted to the whole walk after the fact)")
      ->check(CLI::IsMember({"none", "best-fit"}));
  app.add_option("--config", o->config, "floorposed configuration to evaluate with");
  app.add_flag("--json", o->json, "print one JSON object");
  app.add_flag("--no-pick", o->no_pick,
               "drop the recording's wall picks: the wearer is placed by searching the plan");
  app.add_option("--svg", o->svg, "draw the plan, both trajectories and the markers here");
  app.add_option("--track", o->track, "write every scored pose here as CSV");
  app.add_option("--session", o->session,
                 "write the inputs and all the daemon would have published here, as "
                 "`floorpose record` records a live session");
  return [o] { return RunEval(*o); };
}

}  // namespace floorpose::tools
