// The dashboard as a team lead's command view (label browser), tried with two wearers on
// two floors of a building, each with a floorposed of its own, and two browsers: the
// floor selector, zoom by the wheel, a marker placed by a click reaching the other browser
// and surviving a dashboard restart, the no-motion alert with its banner and
// acknowledgement, the "no data" row, and a second dashboard refused its port.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <thread>

// Eigen before httplib.h: glibc's <resolv.h>, which httplib includes, defines _res, a
// parameter name in Eigen.
#include "tests/integration/daemon_fixture.h"
// clang-format off
#include "tests/browser/webdriver.h"
#include "tools/lib/dashboard.h"
// clang-format on

namespace floorpose {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

// The page as a lead sees it: the floors offered, the map, every wearer's dot and row,
// the markers and the alert banner, in CSS pixels.
const char* kLook = R"(
  const out = {devices: {}, markers: [], alerts: []};
  const map = document.querySelector('#map').getBoundingClientRect();
  out.map = {left: map.left, top: map.top, width: map.width, height: map.height};
  out.floors = [...document.querySelectorAll('#plan-select option')].map(
      (o) => ({value: o.value, label: o.textContent}));
  out.floor = document.querySelector('#plan-select').value;
  out.scale_m = Number(document.querySelector('#scale').dataset.metres);
  out.scale_px = document.querySelector('#scale-bar').getBoundingClientRect().width;
  out.north_shown = getComputedStyle(document.querySelector('#north')).display !== 'none';
  for (const row of document.querySelectorAll('#devices tr[data-device]')) {
    const id = row.dataset.device;
    const g = document.querySelector(`g.wearer[data-device="${id}"]`);
    const why = document.querySelector(`#devices tr[data-reason-of="${id}"]`);
    const d = {row: row.innerText, classes: row.className, why: why ? why.innerText : ''};
    if (g) {
      const r = g.querySelector('circle.dot').getBoundingClientRect();
      d.x = r.left + r.width / 2;
      d.y = r.top + r.height / 2;
    }
    out.devices[id] = d;
  }
  for (const g of document.querySelectorAll('g.marker')) {
    const r = g.querySelector('circle.pin').getBoundingClientRect();
    out.markers.push({id: g.dataset.id, classes: g.getAttribute('class'),
                      x: r.left + r.width / 2, y: r.top + r.height / 2});
  }
  const banner = document.querySelector('#alerts');
  out.banner_shown = !banner.hidden;
  for (const a of banner.querySelectorAll('.alert')) {
    const b = a.querySelector('button').getBoundingClientRect();
    out.alerts.push({device: a.dataset.device, text: a.innerText,
                     button: [b.left + b.width / 2, b.top + b.height / 2]});
  }
  return out;)";

// The centre of an element, CSS pixels.
const char* kCentre = R"(
  const r = document.querySelector(arguments[0]).getBoundingClientRect();
  return [r.left + r.width / 2, r.top + r.height / 2];)";

class CommandViewTest : public DaemonTest {
 protected:
  // A building of two floors, each the fixture's room.
  void UseTwoFloors() {
    for (const char* name : {"ground.geojson", "first.geojson"})
      std::ofstream(dir_ / name) << kRoomGeoJson;
    plan_path_ = (dir_ / "building.floors").string();
    std::ofstream(plan_path_) << "# id height plan\n0 0.0 ground.geojson\n1 3.5 first.geojson\n";
  }
  std::unique_ptr<tools::ChildProcess> StartDashboard(const std::string& log, int port) {
    auto d = std::make_unique<tools::ChildProcess>(
        std::vector<std::string>{FLOORPOSE_PATH, "dashboard", "--plan", plan_path_, "--host",
                                 "127.0.0.1", "--port", std::to_string(port), "--domain",
                                 std::to_string(domain_), "--loopback", "--stale-after", "2",
                                 "--name", "hl-test=Alice", "--name", "hl-b=Bob"},
        (dir_ / log).string());
    return d;
  }
  static std::unique_ptr<testing::Browser> OpenBrowser(const fs::path& log, int port) {
    auto b = std::make_unique<testing::Browser>(1280, 800, log.string());
    b->Open("http://127.0.0.1:" + std::to_string(port) + "/");
    return b;
  }
  // Polls the page until pred(page) holds; the last page either way.
  template <typename Pred>
  static json WaitForPage(testing::Browser& b, Pred pred, std::chrono::seconds timeout) {
    const auto end = Clock::now() + timeout;
    json page;
    do {
      page = b.Run(kLook);
      if (pred(page)) return page;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    } while (Clock::now() < end);
    return page;
  }
};

// The fitted map's pixel of a plan point of the 10 m x 6 m room (zoom 1).
Eigen::Vector2d Screen(const json& page, double x, double y) {
  const json& map = page["map"];
  const double w = map["width"], h = map["height"];
  const double s = std::min((w - 48) / 10.0, (h - 48) / 6.0);
  return {map["left"].get<double>() + (w - 10 * s) / 2 + s * x,
          map["top"].get<double>() + (h - 6 * s) / 2 + s * (6 - y)};
}

TEST_F(CommandViewTest, AlertsMarkersZoomAndFloorsAsALeadUsesThem) {
  UseTwoFloors();
  StartDaemon("floor: \"1\"\n");  // Alice, upstairs
  tools::ChildProcess daemon_b(
      {FLOORPOSED_PATH, "--config", WriteConfig("hl-b", "floor: \"0\"\n", "b.conf")},
      (dir_ / "floorposed-b.log").string());
  tools::HeadsetLink link_b(domain_, platform::LoopbackCycloneConfig(), "hl-b");
  ASSERT_TRUE(link_b.WaitForDaemon(seconds(15))) << "second floorposed; log in " << dir_;

  auto dashboard = StartDashboard("dashboard.log", 0);
  const int port = tools::DashboardPortFromLog((dir_ / "dashboard.log").string(), seconds(15));
  ASSERT_GT(port, 0) << "floorpose dashboard did not come up; see " << dir_;
  std::unique_ptr<testing::Browser> lead, other;
  try {
    lead = OpenBrowser(dir_ / "chromedriver.log", port);
    other = OpenBrowser(dir_ / "chromedriver-2.log", port);
  } catch (const std::exception& e) {
    FAIL() << "headless Chromium: " << e.what();
  }

  const sim::DemoWalk alice_walk = Walk(0.0, 1);
  ASSERT_NO_FATAL_FAILURE(PickAndWalk(alice_walk));
  ASSERT_NO_FATAL_FAILURE(PickAndWalk(Walk(0.0, 2, {{9.0, 5.3}, {3.0, 5.3}, {2.8, 1.0}}), link_b));
  const v1::PlanPose alice = link_->plan_poses.back();
  ASSERT_EQ(alice.floor(), "1");

  // The floors of the set, each wearer on its own: Alice's floor on screen once chosen.
  json page = WaitForPage(
      *lead, [](const json& p) { return p["devices"].size() == 2 && p["floors"].size() == 2; },
      seconds(10));
  ASSERT_EQ(page["floors"].size(), 2u) << page.dump(2);
  EXPECT_EQ(page["floors"][0]["label"], "building floor 0");
  EXPECT_EQ(page["floors"][1]["label"], "building floor 1");
  for (testing::Browser* b : {lead.get(), other.get()})
    b->Run(R"(const s = document.querySelector('#plan-select');
              s.value = 'first'; s.dispatchEvent(new Event('change'));)");
  page = WaitForPage(
      *lead, [](const json& p) { return p["devices"]["hl-test"].contains("x"); }, seconds(5));
  ASSERT_TRUE(page["devices"]["hl-test"].contains("x")) << page.dump(2);
  EXPECT_FALSE(page["devices"]["hl-b"].contains("x")) << "Bob is downstairs";
  EXPECT_NE(page["devices"]["hl-b"]["row"].get<std::string>().find("building floor 0"),
            std::string::npos)
      << page["devices"]["hl-b"]["row"];
  const Eigen::Vector2d at = Screen(page, alice.x(), alice.y());
  EXPECT_NEAR(page["devices"]["hl-test"]["x"].get<double>(), at.x(), 2.0);
  EXPECT_NEAR(page["devices"]["hl-test"]["y"].get<double>(), at.y(), 2.0);
  // The scale bar says what its pixels are.
  const double s = std::min((page["map"]["width"].get<double>() - 48) / 10.0,
                            (page["map"]["height"].get<double>() - 48) / 6.0);
  EXPECT_NEAR(page["scale_px"].get<double>(), page["scale_m"].get<double>() * s, 1.0);
  EXPECT_FALSE(page["north_shown"].get<bool>()) << "the room is not georeferenced";

  // Zoom in by the wheel about a point: the dot moves away from it by the zoom factor
  // (the page zooms by exp(0.002 per pixel of wheel)).
  const Eigen::Vector2d about(page["map"]["left"].get<double>() + 300,
                              page["map"]["top"].get<double>() + 250);
  lead->Wheel(about.x(), about.y(), -100);
  const double zoom = std::exp(0.2);
  const Eigen::Vector2d want = about + zoom * (at - about);
  page = WaitForPage(
      *lead,
      [&](const json& p) {
        return std::abs(p["devices"]["hl-test"].value("x", 0.0) - want.x()) < 2.0 &&
               std::abs(p["devices"]["hl-test"].value("y", 0.0) - want.y()) < 2.0;
      },
      seconds(3));
  EXPECT_NEAR(page["devices"]["hl-test"]["x"].get<double>(), want.x(), 2.0)
      << "zoomed about " << about.transpose();
  EXPECT_NEAR(page["devices"]["hl-test"]["y"].get<double>(), want.y(), 2.0);
  const json fit = lead->Run(kCentre, json::array({"#zoom-fit"}));
  lead->Click(fit[0], fit[1]);
  // Back at zoom 1 before the clicks below, which aim at the fitted map (Screen). Each
  // aim reads the map's box at that moment, not an earlier look's.
  auto fitted = [&](const json& p) {
    const Eigen::Vector2d a = Screen(p, alice.x(), alice.y());
    return std::abs(p["devices"]["hl-test"].value("x", 0.0) - a.x()) < 2.0 &&
           std::abs(p["devices"]["hl-test"].value("y", 0.0) - a.y()) < 2.0;
  };
  page = WaitForPage(*lead, fitted, seconds(3));
  ASSERT_TRUE(fitted(page)) << "zoom to fit: " << page["devices"]["hl-test"].dump();

  // Alice's way out, asked of her daemon from her row: her floor has no exit, so it is
  // where she came onto the floor, the start of her walk.
  const json way_out =
      lead->Run(kCentre, json::array({"#devices tr[data-ways-of=hl-test] [data-to=exit]"}));
  lead->Click(way_out[0], way_out[1]);
  const char* kRoute = R"(
    const l = document.querySelector('polyline.route.exit[data-device="hl-test"]');
    return l ? l.getAttribute('points').split(' ') : [];)";
  json route;
  for (int i = 0; i < 50 && route.empty(); ++i) {
    route = lead->Run(kRoute);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_GE(route.size(), 2u) << "no way out drawn";
  const std::string end = route.back();
  page = lead->Run(kLook);
  const Eigen::Vector2d start = Screen(page, 1.5, 1.5);
  EXPECT_NEAR(page["map"]["left"].get<double>() + std::stod(end.substr(0, end.find(','))),
              start.x(), 0.3 * s);
  EXPECT_NEAR(page["map"]["top"].get<double>() + std::stod(end.substr(end.find(',') + 1)),
              start.y(), 0.3 * s);

  // A hazard placed by a click at plan (2, 2) upstairs: on the other browser, there.
  const json hazard_button = lead->Run(kCentre, json::array({"#marker-kinds [data-kind=hazard]"}));
  lead->Click(hazard_button[0], hazard_button[1]);
  const Eigen::Vector2d target = Screen(lead->Run(kLook), 2.0, 2.0);
  lead->Click(target.x(), target.y());
  auto has_hazard = [&](const json& p) {
    const Eigen::Vector2d there = Screen(p, 2.0, 2.0);
    for (const json& m : p["markers"])
      if (m["classes"].get<std::string>().find("hazard") != std::string::npos &&
          std::abs(m["x"].get<double>() - there.x()) < 2.0 &&
          std::abs(m["y"].get<double>() - there.y()) < 2.0)
        return true;
    return false;
  };
  page = WaitForPage(*other, has_hazard, seconds(10));
  EXPECT_TRUE(has_hazard(page)) << page["markers"].dump();

  // Alice stops moving, her headset still sending; Bob's data stops altogether.
  std::atomic<bool> beating{true};
  const auto still_from = Clock::now();
  std::thread heartbeat([&] {
    // A pose every 0.3 s of headset time, on the wall clock's beat (no drift from the sends).
    const int64_t stamp0 = alice_walk.steps.back().stamp_ns;
    for (int k = 1; beating; ++k) {
      const int64_t stamp = stamp0 + k * 300'000'000LL;
      std::this_thread::sleep_until(still_from + std::chrono::milliseconds(300 * (k - 1)));
      link_->Send(Topic::kHeadsetPose,
                  tools::ToHeadsetPose(alice_walk.steps.back().slam, kFrame, stamp), stamp);
    }
  });
  auto alert_of = [](const json& p, const std::string& device, const std::string& kind) {
    for (const json& a : p["alerts"])
      if (a["device"] == device && a["text"].get<std::string>().find(kind) != std::string::npos)
        return a;
    return json();
  };
  page = WaitForPage(
      *lead, [&](const json& p) { return !alert_of(p, "hl-test", "NO MOTION").is_null(); },
      seconds(40));
  const double alert_after_s = std::chrono::duration<double>(Clock::now() - still_from).count();
  const std::string png = lead->ScreenshotPng();
  std::ofstream(FLOORPOSE_ALERT_SCREENSHOT, std::ios::binary) << png;
  std::printf("alert after %.1f s; screenshot %s\n", alert_after_s, FLOORPOSE_ALERT_SCREENSHOT);
  const json alice_alert = alert_of(page, "hl-test", "NO MOTION");
  ASSERT_FALSE(alice_alert.is_null()) << page.dump(2);
  EXPECT_LE(alert_after_s, 31.0);
  EXPECT_TRUE(page["banner_shown"].get<bool>());
  // Bob's silence is an alert of its own, in the banner too.
  EXPECT_FALSE(alert_of(page, "hl-b", "NO DATA").is_null()) << page["alerts"].dump();
  EXPECT_EQ(page["alerts"].size(), 2u) << page["alerts"].dump();
  EXPECT_NE(page["devices"]["hl-test"]["classes"].get<std::string>().find("alert"),
            std::string::npos);
  EXPECT_NE(page["devices"]["hl-b"]["row"].get<std::string>().find("no data for"),
            std::string::npos)
      << page["devices"]["hl-b"]["row"];
  // Every state and reason in sight, without hovering.
  EXPECT_NE(page["devices"]["hl-test"]["why"].get<std::string>().find("NO MOTION"),
            std::string::npos);

  // The lead acknowledges Alice: her alert leaves the banner of every browser, her row
  // says who. Bob's stays until a lead acknowledges it on that page.
  lead->Click(alice_alert["button"][0], alice_alert["button"][1]);
  page = WaitForPage(
      *other, [&](const json& p) { return alert_of(p, "hl-test", "NO MOTION").is_null(); },
      seconds(10));
  EXPECT_TRUE(alert_of(page, "hl-test", "NO MOTION").is_null());
  EXPECT_FALSE(alert_of(page, "hl-b", "NO DATA").is_null());
  EXPECT_NE(page["devices"]["hl-test"]["classes"].get<std::string>().find("acknowledged"),
            std::string::npos);
  EXPECT_NE(page["devices"]["hl-test"]["why"].get<std::string>().find("acknowledged by lead"),
            std::string::npos)
      << page["devices"]["hl-test"]["why"];
  const json bob_alert = alert_of(page, "hl-b", "NO DATA");
  other->Click(bob_alert["button"][0], bob_alert["button"][1]);
  page = WaitForPage(
      *other, [](const json& p) { return !p["banner_shown"].get<bool>(); }, seconds(5));
  EXPECT_FALSE(page["banner_shown"].get<bool>()) << page["alerts"].dump();
  beating = false;
  heartbeat.join();

  // A second dashboard on the same port is refused, not half the requests.
  auto intruder = StartDashboard("intruder.log", port);
  for (int i = 0; i < 100 && intruder->Running(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_FALSE(intruder->Running());
  EXPECT_NE(intruder->Terminate(seconds(2)), 0);

  // The dashboard restarts (no state of its own): the daemons kept the marker.
  EXPECT_EQ(dashboard->Terminate(seconds(5)), 0);
  dashboard = StartDashboard("dashboard-2.log", port);
  ASSERT_GT(tools::DashboardPortFromLog((dir_ / "dashboard-2.log").string(), seconds(15)), 0);
  other->Open("http://127.0.0.1:" + std::to_string(port) + "/");
  other->Run(R"(setTimeout(() => { const s = document.querySelector('#plan-select');
                s.value = 'first'; s.dispatchEvent(new Event('change')); }, 500);)");
  page = WaitForPage(*other, has_hazard, seconds(10));
  EXPECT_TRUE(has_hazard(page)) << page["markers"].dump();

  lead.reset();
  other.reset();
  EXPECT_EQ(dashboard->Terminate(seconds(5)), 0);
  EXPECT_EQ(daemon_b.Terminate(seconds(5)), 0);
}

}  // namespace
}  // namespace floorpose
