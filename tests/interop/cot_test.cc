// floorpose as seen from ATAK (label interop): a real floorposed and `floorpose cot` on a
// georeferenced room send Cursor-on-Target over UDP multicast on loopback; a Node.js
// receiver parses every event with @tak-ps/node-cot, the library TAK tools are written
// with. Each wearer event must name the wearer (uid, callsign, type) and put it within
// 0.5 m of its plan position, by a conversion independent of ours (WGS84 radii of
// curvature); a marker placed by the wearer arrives as a point. The dashboard's --cot
// sends the same to a receiver of its own.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "tests/integration/daemon_fixture.h"
#include "tools/lib/dashboard.h"

namespace floorpose {
namespace {

using nlohmann::json;

constexpr double kLon0 = 8.6724, kLat0 = 49.4177, kRotationDeg = 30.0;

// Plan metres to (lat, lon) about the origin, on the tangent plane from the WGS84 radii of
// curvature (millimetres off PROJ's azimuthal equidistant over a room).
Eigen::Vector2d LatLon(double x, double y) {
  constexpr double a = 6378137.0, e2 = 6.69437999014e-3;
  const double phi = kLat0 * M_PI / 180, r = kRotationDeg * M_PI / 180;
  const double east = std::cos(r) * x - std::sin(r) * y, north = std::sin(r) * x + std::cos(r) * y;
  const double w = 1 - e2 * std::sin(phi) * std::sin(phi);
  const double m = a * (1 - e2) / std::pow(w, 1.5), n = a / std::sqrt(w);
  return {kLat0 + north / m * 180 / M_PI, kLon0 + east / (n * std::cos(phi)) * 180 / M_PI};
}

// Where an event puts its point, (lat, lon).
Eigen::Vector2d At(const json& event) {
  return {event["lat"].get<double>(), event["lon"].get<double>()};
}

// Metres between two (lat, lon) a few metres apart.
double Metres(const Eigen::Vector2d& p, const Eigen::Vector2d& q) {
  const double phi = kLat0 * M_PI / 180;
  return std::hypot((p.x() - q.x()) * M_PI / 180 * 6371000,
                    (p.y() - q.y()) * M_PI / 180 * 6371000 * std::cos(phi));
}

// The events a receiver has written so far, one JSON object a line.
std::vector<json> ReadEvents(const fs::path& path) {
  std::vector<json> events;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line))
    if (!line.empty()) events.push_back(json::parse(line));
  return events;
}

using CotTest = DaemonTest;

TEST_F(CotTest, AtakSeesTheWearerWhereTheDaemonPutsItAndTheMarkersPlaced) {
  ASSERT_TRUE(fs::exists(NODE_COT_MODULE))
      << "@tak-ps/node-cot is not installed (tools/dev.sh test installs it into build/npm)";
  // The room, georeferenced: origin and the plan's +x 30 degrees north of east.
  std::string plan = kRoomGeoJson;
  plan.replace(plan.find("\"features\""), 0,
               "\"properties\": {\"georeference\": {\"origin\": [" + std::to_string(kLon0) + ", " +
                   std::to_string(kLat0) + "], \"rotation_deg\": " + std::to_string(kRotationDeg) +
                   "}}, ");
  std::ofstream(plan_path_) << plan;
  StartDaemon();

  const int port = 40000 + static_cast<int>(domain_ % 20000);
  const fs::path events = dir_ / "cot.jsonl";
  tools::ChildProcess receiver({NODE_PATH, COT_RECEIVER, "239.2.3.1", std::to_string(port),
                                "127.0.0.1", "40", events.string()},
                               (dir_ / "receiver.log").string());
  ASSERT_TRUE(receiver.started());
  for (int i = 0; i < 200 && !fs::exists(events.string() + ".ready"); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_TRUE(fs::exists(events.string() + ".ready"))
      << "the Node.js receiver did not start (is Node.js installed?); see " << dir_;
  tools::ChildProcess cot(
      {FLOORPOSE_PATH, "cot", "--plan", plan_path_, "--to",
       "udp://239.2.3.1:" + std::to_string(port), "--interface", "127.0.0.1", "--domain",
       std::to_string(domain_), "--loopback", "--name", "hl-test=Alice", "--ground-hae", "110"},
      (dir_ / "cot.log").string());
  ASSERT_TRUE(cot.started());
  // The dashboard's --cot does the same, to a receiver of its own.
  const fs::path dashboard_events = dir_ / "dashboard-cot.jsonl";
  tools::ChildProcess dashboard_receiver(
      {NODE_PATH, COT_RECEIVER, "239.2.3.1", std::to_string(port + 1), "127.0.0.1", "40",
       dashboard_events.string()},
      (dir_ / "dashboard-receiver.log").string());
  for (int i = 0; i < 200 && !fs::exists(dashboard_events.string() + ".ready"); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  tools::ChildProcess dashboard(
      {FLOORPOSE_PATH, "dashboard", "--plan", plan_path_, "--host", "127.0.0.1", "--port", "0",
       "--domain", std::to_string(domain_), "--loopback", "--name", "hl-test=Alice", "--cot",
       "udp://239.2.3.1:" + std::to_string(port + 1), "--cot-interface", "127.0.0.1"},
      (dir_ / "dashboard.log").string());
  ASSERT_GT(tools::DashboardPortFromLog((dir_ / "dashboard.log").string(), seconds(15)), 0)
      << "see " << dir_;
  std::this_thread::sleep_for(std::chrono::seconds(2));  // cot joins the domain

  const sim::DemoWalk walk = Walk(0.0, 5);
  ASSERT_NO_FATAL_FAILURE(PickAndWalk(walk));
  v1::Command place;
  place.mutable_place_marker()->set_kind(v1::Marker::VICTIM);
  place.mutable_place_marker()->set_text("trapped");
  *place.mutable_place_marker()->mutable_headset_point() =
      tools::ToHeadsetPose(walk.steps.back().slam, kFrame, 0).position();
  const auto placed = link_->Request(place, seconds(5));
  ASSERT_TRUE(placed && placed->ok()) << (placed ? placed->message() : "no reply");

  // Every event parsed; the last pose and the marker arrived.
  const v1::PlanPose last = link_->plan_poses.back();
  std::vector<json> got;
  const auto deadline = std::chrono::steady_clock::now() + seconds(15);
  bool have_last = false, have_marker = false;
  while (std::chrono::steady_clock::now() < deadline && !(have_last && have_marker)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    got = ReadEvents(events);
    have_last = false, have_marker = false;
    for (const json& e : got) {
      if (e.contains("error")) continue;
      have_marker |= e["uid"] == "floorpose-marker-" + placed->marker().id();
      have_last |=
          e["uid"] == "floorpose-hl-test" && Metres(At(e), LatLon(last.x(), last.y())) < 0.5;
    }
  }
  ASSERT_GT(got.size(), 10u) << "see " << dir_;
  EXPECT_TRUE(have_last) << "no event at the wearer's last plan position";
  EXPECT_TRUE(have_marker) << "no event for the marker";
  size_t wearer_events = 0;
  for (const json& e : got) {
    ASSERT_FALSE(e.contains("error")) << e.dump();
    if (e["uid"] != "floorpose-hl-test") continue;
    ++wearer_events;
    EXPECT_EQ(e["type"], "a-f-G-U-C");
    EXPECT_EQ(e["callsign"], "Alice");
    EXPECT_NEAR(e["hae"].get<double>(), 110.0, 1e-6) << "ground, floor 0";
    // At one of the poses the daemon published (each is sent as it comes).
    double nearest = INFINITY;
    for (const v1::PlanPose& p : link_->plan_poses)
      nearest = std::min(nearest, Metres(At(e), LatLon(p.x(), p.y())));
    EXPECT_LT(nearest, 0.5) << e.dump();
    EXPECT_GT(e["ce"].get<double>(), 0.0);
  }
  EXPECT_GT(wearer_events, walk.steps.size() / 2);
  for (const json& e : got)
    if (e["uid"] == "floorpose-marker-" + placed->marker().id()) {
      EXPECT_EQ(e["type"], "b-r-f-h-c");
      EXPECT_EQ(e["callsign"], "victim: trapped");
      EXPECT_LT(Metres(At(e), LatLon(placed->marker().x(), placed->marker().y())), 0.5);
    }
  // The dashboard's events: the same wearer, where the daemon put it last.
  std::vector<json> from_dashboard;
  bool dashboard_has_last = false;
  for (int i = 0; i < 50 && !dashboard_has_last; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    from_dashboard = ReadEvents(dashboard_events);
    for (const json& e : from_dashboard)
      dashboard_has_last |= !e.contains("error") && e["uid"] == "floorpose-hl-test" &&
                            e["callsign"] == "Alice" &&
                            Metres(At(e), LatLon(last.x(), last.y())) < 0.5;
  }
  EXPECT_TRUE(dashboard_has_last) << from_dashboard.size() << " events from the dashboard";
  EXPECT_EQ(dashboard.Terminate(seconds(5)), 0) << "see " << dir_;
  EXPECT_EQ(cot.Terminate(seconds(5)), 0) << "see " << dir_;
  receiver.Terminate(seconds(2));
  dashboard_receiver.Terminate(seconds(2));
}

}  // namespace
}  // namespace floorpose
