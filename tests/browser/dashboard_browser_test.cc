// The dashboard end to end (label browser): two wearers walk through the room, each with
// a floorposed of its own on one loopback DDS domain; `floorpose dashboard` serves the
// page to Debian's headless Chromium, driven over WebDriver. The page must show both
// where their daemons put them, to the pixel, grey the one that stopped, and tint what
// the team explored.
#include <gtest/gtest.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>

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

// What the page shows of each wearer, read through the DOM in CSS pixels.
const char* kProbe = R"(
  const out = {devices: {}};
  const map = document.querySelector('#map').getBoundingClientRect();
  out.map = {left: map.left, top: map.top, width: map.width, height: map.height};
  out.dpr = window.devicePixelRatio;
  for (const id of arguments[0]) {
    const g = document.querySelector(`g.wearer[data-device="${id}"]`);
    const row = document.querySelector(`#devices tr[data-device="${id}"]`);
    if (!g || !row) continue;
    const dot = g.querySelector('circle.dot');
    const r = dot.getBoundingClientRect();
    out.devices[id] = {x: r.left + r.width / 2, y: r.top + r.height / 2,
                       classes: g.getAttribute('class'), fill: getComputedStyle(dot).fill,
                       name: g.querySelector('text').textContent,
                       title: g.querySelector('title').textContent,
                       row: row.innerText, row_stale: row.classList.contains('stale'),
                       trail: document.querySelector(`polyline.trail[data-device="${id}"]`)
                                  .getAttribute('points').split(' ')};
  }
  return out;)";

struct Rgba {
  int r, g, b;
};

// An RGBA image decoded with libpng's simplified API.
struct Image {
  int width = 0, height = 0;
  std::vector<unsigned char> pixels;
  Rgba At(int x, int y) const {
    const size_t i = (static_cast<size_t>(y) * width + x) * 4;
    return {pixels[i], pixels[i + 1], pixels[i + 2]};
  }
};

bool DecodePng(const std::string& png, Image* image) {
  png_image p{};
  p.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&p, png.data(), png.size())) return false;
  p.format = PNG_FORMAT_RGBA;
  image->width = static_cast<int>(p.width);
  image->height = static_cast<int>(p.height);
  image->pixels.resize(PNG_IMAGE_SIZE(p));
  return png_image_finish_read(&p, nullptr, image->pixels.data(), 0, nullptr) != 0;
}

int Distance(Rgba a, Rgba b) {
  return std::max({std::abs(a.r - b.r), std::abs(a.g - b.g), std::abs(a.b - b.b)});
}

using DashboardBrowserTest = DaemonTest;

TEST_F(DashboardBrowserTest, ShowsBothWearersWhereTheirDaemonsPutThemAndGreysTheOneThatStops) {
  // Alice (hl-test, the fixture's daemon and link) and Bob (hl-b), one daemon each.
  // Deterministic: each update of the belief is applied before the next pose, so which
  // poses are RELIABLE (and so the explored map) does not depend on the machine's load.
  StartDaemon("deterministic: true\n");
  tools::ChildProcess daemon_b(
      {FLOORPOSED_PATH, "--config", WriteConfig("hl-b", "deterministic: true\n", "b.conf")},
      (dir_ / "floorposed-b.log").string());
  tools::HeadsetLink link_b(domain_, platform::LoopbackCycloneConfig(), "hl-b");
  ASSERT_TRUE(link_b.WaitForDaemon(seconds(15))) << "second floorposed; log in " << dir_;

  const fs::path dashboard_log = dir_ / "dashboard.log";
  tools::ChildProcess dashboard(
      {FLOORPOSE_PATH, "dashboard", "--plan", plan_path_, "--host", "127.0.0.1", "--port", "0",
       "--domain", std::to_string(domain_), "--loopback", "--stale-after", "2", "--name",
       "hl-test=Alice", "--name", "hl-b=Bob"},
      dashboard_log.string());
  const int port = tools::DashboardPortFromLog(dashboard_log.string(), seconds(15));
  ASSERT_GT(port, 0) << "floorpose dashboard did not come up; see " << dashboard_log;

  std::unique_ptr<testing::Browser> browser;
  try {
    browser = std::make_unique<testing::Browser>(1280, 800, (dir_ / "chromedriver.log").string());
  } catch (const std::exception& e) {
    FAIL() << "headless Chromium: " << e.what();
  }
  browser->Open("http://127.0.0.1:" + std::to_string(port) + "/");

  ASSERT_NO_FATAL_FAILURE(PickAndWalk(Walk(/*pick_error_m=*/0.0, 1)));
  const sim::DemoWalk bob_walk = Walk(0.0, 2, {{9.0, 5.3}, {3.0, 5.3}, {2.8, 1.0}});
  ASSERT_NO_FATAL_FAILURE(PickAndWalk(bob_walk, link_b));

  // Alice stops; Bob stands still but his headset goes on, a pose every 0.3 s.
  int64_t stamp = bob_walk.steps.back().stamp_ns;
  auto bob_heartbeat = [&] {
    stamp += 300'000'000;
    link_b.Send(Topic::kHeadsetPose,
                tools::ToHeadsetPose(bob_walk.steps.back().slam, kFrame, stamp), stamp);
  };
  const json ids = json::array({"hl-test", "hl-b"});
  json page;
  const auto deadline = std::chrono::steady_clock::now() + seconds(20);
  while (std::chrono::steady_clock::now() < deadline) {
    bob_heartbeat();
    link_b.WaitUntil([] { return false; }, std::chrono::milliseconds(300));
    link_->Poll();
    page = browser->Run(kProbe, json::array({ids}));
    const json& d = page["devices"];
    if (d.contains("hl-test") && d.contains("hl-b") &&
        d["hl-test"]["classes"].get<std::string>().find("stale") != std::string::npos &&
        d["hl-b"]["classes"].get<std::string>().find("stale") == std::string::npos)
      break;
  }
  // One more heartbeat answered, so that Bob's last plan pose is the one on the page.
  const size_t answered = link_b.plan_poses.size();
  bob_heartbeat();
  ASSERT_TRUE(link_b.WaitUntil([&] { return link_b.plan_poses.size() > answered; }, seconds(5)));
  link_b.WaitUntil([] { return false; }, std::chrono::milliseconds(400));
  page = browser->Run(kProbe, json::array({ids}));
  const std::string png = browser->ScreenshotPng();
  std::ofstream(FLOORPOSE_SCREENSHOT, std::ios::binary) << png;
  std::printf("screenshot: %s\npage: %s\n", FLOORPOSE_SCREENSHOT, page.dump().c_str());

  const json& devices = page["devices"];
  ASSERT_TRUE(devices.contains("hl-test") && devices.contains("hl-b")) << page.dump(2);
  const json& alice = devices["hl-test"];
  const json& bob = devices["hl-b"];
  EXPECT_EQ(alice["name"], "Alice");
  EXPECT_EQ(bob["name"], "Bob");
  EXPECT_NE(alice["classes"].get<std::string>().find("stale"), std::string::npos) << page.dump(2);
  EXPECT_TRUE(alice["row_stale"].get<bool>());
  EXPECT_EQ(alice["fill"], "rgb(154, 154, 154)");  // --stale
  EXPECT_EQ(bob["classes"].get<std::string>().find("stale"), std::string::npos) << page.dump(2);
  EXPECT_FALSE(bob["row_stale"].get<bool>());

  // The room spans (0, 0) to (10, 6) m, fitted into the map with a 24 px margin, y up.
  const json& map = page["map"];
  const double w = map["width"], h = map["height"];
  const double s = std::min((w - 48) / 10.0, (h - 48) / 6.0);
  auto screen = [&](double x, double y) {
    return Eigen::Vector2d(map["left"].get<double>() + (w - 10 * s) / 2 + s * x,
                           map["top"].get<double>() + (h - 6 * s) / 2 + s * (6 - y));
  };
  const v1::PlanPose& alice_pose = link_->plan_poses.back();
  const v1::PlanPose& bob_pose = link_b.plan_poses.back();
  const Eigen::Vector2d alice_px = screen(alice_pose.x(), alice_pose.y());
  const Eigen::Vector2d bob_px = screen(bob_pose.x(), bob_pose.y());
  EXPECT_NEAR(alice["x"].get<double>(), alice_px.x(), 2.0);
  EXPECT_NEAR(alice["y"].get<double>(), alice_px.y(), 2.0);
  EXPECT_NEAR(bob["x"].get<double>(), bob_px.x(), 2.0);
  EXPECT_NEAR(bob["y"].get<double>(), bob_px.y(), 2.0);
  // Alice's trail: every pose of her walk, ending where she stands (in the map's pixels).
  const json& trail = alice["trail"];
  EXPECT_EQ(trail.size(), link_->plan_poses.size());
  if (!trail.empty()) {
    const std::string last = trail.back();
    EXPECT_NEAR(map["left"].get<double>() + std::stod(last.substr(0, last.find(','))), alice_px.x(),
                2.0);
    EXPECT_NEAR(map["top"].get<double>() + std::stod(last.substr(last.find(',') + 1)), alice_px.y(),
                2.0);
  }
  // The reason of Bob's reliability is there on hover.
  EXPECT_NE(bob["title"].get<std::string>().find(bob_pose.reliability().reason()),
            std::string::npos)
      << bob["title"];
  EXPECT_NE(alice["title"].get<std::string>().find("no data"), std::string::npos);

  // And in the pixels the browser drew: Alice's dot grey, Bob's in his reliability's
  // colour, the inner wall (x = 4 m, y 0 to 3.5 m) dark.
  Image image;
  ASSERT_TRUE(DecodePng(png, &image)) << "screenshot is not a PNG";
  const double dpr = page["dpr"];
  auto pixel = [&](const Eigen::Vector2d& css) {
    return image.At(static_cast<int>(std::lround(css.x() * dpr)),
                    static_cast<int>(std::lround(css.y() * dpr)));
  };
  const Rgba grey{154, 154, 154}, green{46, 158, 68}, amber{232, 163, 23}, red{208, 49, 45};
  const v1::Reliability::Flag bob_flag = bob_pose.reliability().flag();
  const Rgba bob_colour = bob_flag == v1::Reliability::RELIABLE   ? green
                          : bob_flag == v1::Reliability::DEGRADED ? amber
                                                                  : red;
  EXPECT_LE(Distance(pixel(alice_px), grey), 24);
  EXPECT_LE(Distance(pixel(bob_px), bob_colour), 24);
  const Eigen::Vector2d wall = screen(4.0, 1.75) * dpr;
  int darkest = 255;
  for (int dy = -3; dy <= 3; ++dy)
    for (int dx = -3; dx <= 3; ++dx) {
      const Rgba c = image.At(static_cast<int>(wall.x()) + dx, static_cast<int>(wall.y()) + dy);
      darkest = std::min(darkest, std::max({c.r, c.g, c.b}));
    }
  EXPECT_LT(darkest, 90) << "no wall drawn where the inner wall is";
  // The team's explored map tints the room where the two walked and looked.
  const Eigen::Vector2d south_west = screen(0, 0) * dpr, north_east = screen(10, 6) * dpr;
  size_t tinted = 0, pixels = 0;
  for (int y = static_cast<int>(north_east.y()) + 4; y < static_cast<int>(south_west.y()) - 4; ++y)
    for (int x = static_cast<int>(south_west.x()) + 4; x < static_cast<int>(north_east.x()) - 4;
         ++x) {
      const Rgba c = image.At(x, y);
      tinted += c.b - c.r > 25;
      ++pixels;
    }
  EXPECT_GT(static_cast<double>(tinted) / static_cast<double>(pixels), 0.2)
      << tinted << " of " << pixels << " pixels of the room tinted as explored";

  browser.reset();
  EXPECT_EQ(dashboard.Terminate(seconds(5)), 0) << "see " << dashboard_log;
  EXPECT_EQ(daemon_b.Terminate(seconds(5)), 0);
}

}  // namespace
}  // namespace floorpose
