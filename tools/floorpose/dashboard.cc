// `floorpose dashboard`: the team lead's live map of every wearer, served to browsers on
// the local network (tools/lib/dashboard.h; the page is in tools/dashboard/).
#include <spdlog/spdlog.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <thread>

#include "platform/floor_plan_io.h"
#include "tools/floorpose/commands.h"
#include "tools/floorpose/dds_options.h"
#include "tools/lib/dashboard.h"

namespace floorpose::tools {
namespace {

struct DashboardCommandOptions {
  std::string plan;
  std::string plans_dir;
  std::vector<std::string> names;  // ID=NAME
  std::string security_dir;
  std::string identity = "dashboard";
  std::string state_dir;
  std::string cot_to;  // empty: no CoT
  CotOptions cot;
  DashboardServerOptions server;
  DdsOptions dds;
};

int RunDashboard(DashboardCommandOptions o) {
  if (!ParseDeviceNames(o.names, "NAME", &o.server.dashboard.names)) return 2;
  if (!(o.server.dashboard.stale_after_s > 0)) {
    spdlog::error("--stale-after must be positive");
    return 2;
  }
  std::vector<DashboardPlan> plans;
  if (!LoadDashboardPlans(o.plan, o.plans_dir, &plans)) return 1;
  if (o.state_dir.empty())
    if (const char* systemd_dir = std::getenv("STATE_DIRECTORY"))
      o.state_dir = std::string(systemd_dir).substr(0, std::string(systemd_dir).find(':'));
  if (!o.state_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(o.state_dir, ec);
    o.server.markers_path = (std::filesystem::path(o.state_dir) / "markers.pb").string();
  }
  if (!o.cot_to.empty()) {
    o.cot.to = o.cot_to;
    o.cot.names = o.server.dashboard.names;
    o.server.cot = o.cot;
  }
  o.server.domain_id = o.dds.domain_id;
  o.server.cyclone_config = o.dds.Config();
  if (!o.security_dir.empty()) {
    o.server.security = platform::SecurityFilesIn(o.security_dir, o.identity);
    spdlog::info("DDS Security: identity '{}' from {}", o.identity, o.security_dir);
  }

  // SIGINT and SIGTERM are taken by this thread alone, before any other starts.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  std::unique_ptr<Dashboard> dashboard;
  try {
    dashboard = std::make_unique<Dashboard>(o.server, std::move(plans));
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  spdlog::info("dashboard on http://{}:{}/ (DDS domain {})", o.server.host, dashboard->port(),
               o.server.domain_id);
  std::thread server([&] { dashboard->Serve(); });
  int sig = 0;
  sigwait(&signals, &sig);
  spdlog::info("signal {}: stopping", sig);
  dashboard->Stop();
  server.join();
  return 0;
}

}  // namespace

bool ParseDeviceNames(const std::vector<std::string>& specs, const char* value,
                      std::map<std::string, std::string>* names) {
  for (const std::string& n : specs) {
    const size_t eq = n.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == n.size()) {
      spdlog::error("--name {}: expected DEVICE_ID={}", n, value);
      return false;
    }
    (*names)[n.substr(0, eq)] = n.substr(eq + 1);
  }
  return true;
}

Run AddDashboardCommand(CLI::App& app) {
  auto o = std::make_shared<DashboardCommandOptions>();
  auto* plan = app.add_option("--plan", o->plan, "the floor plan to draw");
  app.add_option("--plans", o->plans_dir, "a directory of floor plans (as the daemon's plan_dir)")
      ->excludes(plan);
  app.add_option("--port", o->server.port, "HTTP port (0: any free one, logged)")
      ->capture_default_str();
  app.add_option("--host", o->server.host, "address to listen on")->capture_default_str();
  app.add_option("--stale-after", o->server.dashboard.stale_after_s,
                 "seconds without data after which a wearer is greyed")
      ->capture_default_str();
  app.add_option("--name", o->names, "DEVICE_ID=NAME: the name shown for a device (repeatable)");
  app.add_option("--security-dir", o->security_dir,
                 "join a DDS-Security domain with the files tools/make-dds-security.sh made here");
  app.add_option("--identity", o->identity, "the identity (NAME.pem, NAME.key) in --security-dir")
      ->capture_default_str();
  app.add_option("--state-dir", o->state_dir,
                 "keep the team's markers here across restarts (default: systemd's "
                 "$STATE_DIRECTORY, else not kept)");
  app.add_option("--lead", o->server.name,
                 "who places markers and acknowledges alerts from this dashboard")
      ->capture_default_str();
  app.add_option("--cot", o->cot_to,
                 "also send the wearers and markers of georeferenced plans as Cursor-on-Target "
                 "to udp://239.2.3.1:6969 (TAK's default) or tcp://HOST:PORT (docs/cot.md)");
  app.add_option("--cot-interface", o->cot.interface, "send CoT multicast out of this address");
  app.add_option("--ground-hae", o->cot.ground_hae_m,
                 "height of the plans' zero above the WGS84 ellipsoid, metres (CoT's hae)")
      ->capture_default_str();
  o->dds.Add(app);
  return [o] { return RunDashboard(*o); };
}

}  // namespace floorpose::tools
