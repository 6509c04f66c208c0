// `floorpose cot`: every wearer of a georeferenced plan, and the team's markers, as
// Cursor-on-Target for ATAK, WinTAK or a TAK server (tools/lib/cot.h, docs/cot.md).
#include <spdlog/spdlog.h>

#include <csignal>
#include <memory>

#include "platform/dds.h"
#include "tools/floorpose/commands.h"
#include "tools/floorpose/dds_options.h"
#include "tools/lib/cot.h"
#include "tools/lib/dashboard.h"

namespace floorpose::tools {
namespace {

using platform::Topic;

struct CotCommandOptions {
  std::string plan, plans_dir;
  std::vector<std::string> names;  // ID=CALLSIGN
  CotOptions cot;
  DdsOptions dds;
};

volatile std::sig_atomic_t g_stop = 0;

int RunCot(CotCommandOptions o) {
  if (!ParseDeviceNames(o.names, "CALLSIGN", &o.cot.names)) return 2;
  std::vector<DashboardPlan> plans;
  if (!LoadDashboardPlans(o.plan, o.plans_dir, &plans)) return 1;
  const std::vector<CotPlan> placed = CotPlansOf(plans);
  if (placed.empty()) {
    spdlog::error(
        "no plan is georeferenced: give a WGS84 GeoJSON plan, or one with "
        "properties.georeference (docs/cot.md)");
    return 1;
  }
  CotBridge bridge(placed, o.cot);
  std::string error;
  if (!bridge.Open(&error)) {
    spdlog::error("{}", error);
    return 1;
  }
  std::unique_ptr<platform::Participant> participant;
  std::vector<std::unique_ptr<platform::Reader>> readers;
  std::unique_ptr<platform::Waiter> waiter;
  try {
    participant = std::make_unique<platform::Participant>(o.dds.domain_id, o.dds.Config());
    waiter = std::make_unique<platform::Waiter>(*participant);
    for (Topic t : {Topic::kStatus, Topic::kPlanPose, Topic::kMarker}) {
      readers.push_back(std::make_unique<platform::Reader>(*participant, t));
      waiter->Attach(*readers.back());
    }
  } catch (const std::exception& e) {
    spdlog::error("DDS: {}", e.what());
    return 1;
  }
  std::signal(SIGINT, [](int) { g_stop = 1; });
  std::signal(SIGTERM, [](int) { g_stop = 1; });
  spdlog::info("CoT to {} for {} georeferenced plans (DDS domain {})", o.cot.to, placed.size(),
               o.dds.domain_id);
  size_t malformed = 0;
  while (!g_stop) {
    waiter->Wait(std::chrono::milliseconds(200));
    for (auto& reader : readers)
      for (const platform::Envelope& e : reader->Take(256)) {
        bool ok = false;
        if (reader->topic() == Topic::kStatus) {
          v1::DaemonStatus m;
          if ((ok = m.ParseFromString(e.payload))) bridge.OnStatus(e.device_id, m);
        } else if (reader->topic() == Topic::kPlanPose) {
          v1::PlanPose m;
          if ((ok = m.ParseFromString(e.payload))) bridge.OnPlanPose(e.device_id, m);
        } else {
          v1::Marker m;
          if ((ok = m.ParseFromString(e.payload))) bridge.OnMarker(m);
        }
        if (!ok && malformed++ % 100 == 0)
          spdlog::warn("{} malformed message(s) so far, the latest on {}", malformed,
                       platform::TopicName(reader->topic()));
      }
  }
  spdlog::info("stopping: {} CoT events sent", bridge.sent());
  return 0;
}

}  // namespace

Run AddCotCommand(CLI::App& app) {
  auto o = std::make_shared<CotCommandOptions>();
  auto* plan = app.add_option("--plan", o->plan, "the plan (or .floors set) the wearers are on");
  app.add_option("--plans", o->plans_dir, "a directory of plans (as the daemon's plan_dir)")
      ->excludes(plan);
  app.add_option("--to", o->cot.to,
                 "udp://GROUP:PORT (multicast), udp://HOST:PORT or tcp://HOST:PORT")
      ->capture_default_str();
  app.add_option("--interface", o->cot.interface, "send multicast out of this address");
  app.add_option("--name", o->names, "DEVICE_ID=CALLSIGN (repeatable; default the id)");
  app.add_option("--ground-hae", o->cot.ground_hae_m,
                 "height of the plans' zero above the WGS84 ellipsoid, metres")
      ->capture_default_str();
  app.add_option("--stale", o->cot.stale_s, "seconds a receiver shows an event without a new one")
      ->capture_default_str();
  o->dds.Add(app);
  return [o] { return RunCot(*o); };
}

}  // namespace floorpose::tools
