// The dashboard's model (what each browser is sent) and its server over loopback DDS and
// HTTP: trails, re-projected tracks, staleness, late and bad input.
#include "tools/lib/dashboard.h"

#include <gtest/gtest.h>
#include <png.h>
#include <zlib.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <thread>

#include "platform/dds.h"
#include "platform/floor_plan_io.h"
#include "tests/daemon_test_util.h"
// clang-format off
#include <httplib.h>  // after Eigen: glibc's <resolv.h> defines _res, a name in Eigen
// clang-format on

namespace floorpose::tools {
namespace {

using json = nlohmann::json;
using Clock = DashboardState::Clock;
using std::chrono::milliseconds;
using std::chrono::seconds;

v1::PlanPose Pose(double x, double y, int64_t stamp_ns,
                  v1::Reliability::Flag flag = v1::Reliability::RELIABLE) {
  v1::PlanPose p;
  p.set_x(x);
  p.set_y(y);
  p.set_heading(0.5);
  p.set_source_stamp_ns(stamp_ns);
  p.mutable_reliability()->set_flag(flag);
  p.mutable_reliability()->set_probability(0.9);
  p.mutable_reliability()->set_reason("registered");
  return p;
}

json FrameOf(const DashboardState& state, DashboardState::Cursor* cursor, Clock::time_point now) {
  return json::parse(state.Frame(cursor, now));
}

const json* Device(const json& frame, const std::string& id) {
  for (const json& d : frame["devices"])
    if (d["id"] == id) return &d;
  return nullptr;
}

TEST(DashboardStateTest, SendsTheWholePictureFirstThenOnlyWhatChanged) {
  DashboardOptions o;
  o.names["hl-a"] = "Alice";
  DashboardState state(o);
  const auto t0 = Clock::now();
  for (int k = 0; k < 3; ++k) state.OnPlanPose("hl-a", Pose(k, 1.0, k * 300'000'000), t0);
  v1::DaemonStatus status;
  status.set_state(v1::DaemonStatus::TRACKING);
  status.set_plan_id("office");
  state.OnStatus("hl-b", status, t0);

  DashboardState::Cursor browser;
  const json first = FrameOf(state, &browser, t0);
  ASSERT_EQ(first["devices"].size(), 2u);
  const json& a = *Device(first, "hl-a");
  EXPECT_EQ(a["name"], "Alice");
  EXPECT_EQ(a["pose"]["x"], 2.0);
  EXPECT_EQ(a["pose"]["flag"], "reliable");
  EXPECT_EQ(a["trail"]["reset"], true);
  EXPECT_EQ(a["trail"]["points"].size(), 3u);
  const json& b = *Device(first, "hl-b");
  EXPECT_EQ(b["name"], "hl-b");
  EXPECT_EQ(b["plan"], "office");
  EXPECT_EQ(b["state"], "TRACKING");
  EXPECT_FALSE(b.contains("pose"));

  // Nothing new: no device, but every device's age.
  const json quiet = FrameOf(state, &browser, t0 + milliseconds(500));
  EXPECT_TRUE(quiet["devices"].empty());
  EXPECT_EQ(quiet["ages"]["hl-a"], 0.5);

  // One new pose: that device alone, with the one new trail point.
  state.OnPlanPose("hl-a", Pose(3, 1.0, 900'000'000, v1::Reliability::DEGRADED), t0);
  const json next = FrameOf(state, &browser, t0);
  ASSERT_EQ(next["devices"].size(), 1u);
  EXPECT_EQ(next["devices"][0]["trail"]["reset"], false);
  EXPECT_EQ(next["devices"][0]["trail"]["points"], json::parse(R"([[3.0, 1.0, "degraded"]])"));

  // A second browser connecting now gets the whole trail.
  DashboardState::Cursor late;
  EXPECT_EQ((*Device(FrameOf(state, &late, t0), "hl-a"))["trail"]["points"].size(), 4u);
}

TEST(DashboardStateTest, ALatePoseIsHistoryAndABadOneIsDropped) {
  DashboardState state({});
  const auto t0 = Clock::now();
  state.OnPlanPose("hl-a", Pose(5, 5, 2'000'000'000), t0);
  state.OnPlanPose("hl-a", Pose(1, 1, 1'000'000'000), t0);  // older: not where the wearer is
  state.OnPlanPose("hl-a", Pose(NAN, 1, 3'000'000'000), t0);
  state.OnPlanPose("hl-a", Pose(1, INFINITY, 3'000'000'000), t0);
  DashboardState::Cursor c;
  const json f = FrameOf(state, &c, t0);
  const json& a = *Device(f, "hl-a");
  EXPECT_EQ(a["pose"]["x"], 5.0);
  EXPECT_EQ(a["trail"]["points"].size(), 1u);
}

TEST(DashboardStateTest, AHeadsetWhoseClockStartsAgainIsFollowed) {
  DashboardState state({});
  const auto t0 = Clock::now();
  state.OnPlanPose("hl-a", Pose(5, 5, 900'000'000'000), t0);
  state.OnPlanPose("hl-a", Pose(6, 5, 900'300'000'000), t0);
  // The app restarted: its stamps begin again near 0.
  state.OnPlanPose("hl-a", Pose(7, 5, 300'000'000), t0);
  state.OnPlanPose("hl-a", Pose(8, 5, 600'000'000), t0);
  DashboardState::Cursor c;
  const json f = FrameOf(state, &c, t0);
  const json& a = *Device(f, "hl-a");
  EXPECT_EQ(a["pose"]["x"], 8.0);
  ASSERT_EQ(a["trail"]["points"].size(), 2u);
}

TEST(DashboardStateTest, ANewTrackReplacesTheTrailAndKeepsWhatCameAfterIt) {
  DashboardState state({});
  const auto t0 = Clock::now();
  for (int k = 0; k < 5; ++k) state.OnPlanPose("hl-a", Pose(k, 0, k * 100), t0);
  DashboardState::Cursor c;
  FrameOf(state, &c, t0);
  // The daemon re-projected poses 0..3 under a new alignment (shifted 1 m in y); pose 4
  // came after the track.
  v1::PlanTrack track;
  for (int k = 0; k < 4; ++k) *track.add_poses() = Pose(k, 1, k * 100);
  state.OnPlanTrack("hl-a", track, t0);
  const json f = FrameOf(state, &c, t0);
  const json& trail = (*Device(f, "hl-a"))["trail"];
  EXPECT_EQ(trail["reset"], true);
  ASSERT_EQ(trail["points"].size(), 5u);
  EXPECT_EQ(trail["points"][0][1], 1.0);
  EXPECT_EQ(trail["points"][3][1], 1.0);
  EXPECT_EQ(trail["points"][4][1], 0.0);
  // A pose the track already holds is not added twice.
  state.OnPlanPose("hl-a", Pose(3, 1, 300), t0);
  EXPECT_FALSE((*Device(FrameOf(state, &c, t0), "hl-a")).contains("trail"));
}

TEST(DashboardStateTest, TheTrailKeepsItsLatestPointsAndABrowserThatFellBehindStartsOver) {
  DashboardOptions o;
  o.trail_points = 10;
  DashboardState state(o);
  const auto t0 = Clock::now();
  DashboardState::Cursor c;
  for (int k = 0; k < 8; ++k) state.OnPlanPose("hl-a", Pose(k, 0, k), t0);
  FrameOf(state, &c, t0);
  for (int k = 8; k < 12; ++k) state.OnPlanPose("hl-a", Pose(k, 0, k), t0);
  const json more = (*Device(FrameOf(state, &c, t0), "hl-a"))["trail"];
  EXPECT_EQ(more["reset"], false);
  EXPECT_EQ(more["points"].size(), 4u);
  for (int k = 12; k < 40; ++k) state.OnPlanPose("hl-a", Pose(k, 0, k), t0);
  const json behind = (*Device(FrameOf(state, &c, t0), "hl-a"))["trail"];
  EXPECT_EQ(behind["reset"], true);
  ASSERT_EQ(behind["points"].size(), 10u);
  EXPECT_EQ(behind["points"][0][0], 30.0);
}

TEST(DashboardStateTest, AWearerWithoutPosesGoesStaleEvenWhileItsDaemonReports) {
  DashboardOptions o;
  o.stale_after_s = 2;
  DashboardState state(o);
  const auto t0 = Clock::now();
  state.OnPlanPose("hl-a", Pose(1, 1, 1), t0);
  state.OnPlanPose("hl-b", Pose(2, 2, 1), t0);
  v1::DaemonStatus status;
  state.OnStatus("hl-a", status, t0 + seconds(3));  // the daemon is up, the headset quiet
  state.OnPlanPose("hl-b", Pose(2, 2, 2), t0 + seconds(3));
  state.OnStatus("hl-c", status, t0);  // never a pose: counted from its last message
  DashboardState::Cursor c;
  const json f = FrameOf(state, &c, t0 + seconds(3));
  EXPECT_EQ(f["stale"], json::parse(R"(["hl-a", "hl-c"])"));
  EXPECT_EQ(f["ages"]["hl-a"], 3.0);
  EXPECT_EQ(f["ages"]["hl-b"], 0.0);
}

TEST(DashboardStateTest, BadDeviceIdsAndTooManyDevicesNeitherThrowNorGrowWithoutBound) {
  DashboardOptions o;
  o.max_devices = 3;
  DashboardState state(o);
  const auto t0 = Clock::now();
  state.OnPlanPose(std::string("hl-\xff\xfe", 5), Pose(1, 1, 1), t0);  // not UTF-8
  for (int k = 0; k < 10; ++k) state.OnPlanPose("hl-" + std::to_string(k), Pose(k, 1, 1), t0);
  EXPECT_EQ(state.devices(), 3u);
  DashboardState::Cursor c;
  const json f = FrameOf(state, &c, t0);
  EXPECT_EQ(f["devices"].size(), 3u);
}

// A grid of width x 2 cells on plan `plan`, the bytes as given, zlib-packed.
v1::ExploredMap Explored(const std::string& plan, std::vector<int8_t> cells, uint32_t width = 4,
                         double origin_x = -1.0) {
  v1::ExploredMap m;
  m.set_plan_id(plan);
  m.set_origin_x(origin_x);
  m.set_origin_y(-1.0);
  m.set_cell_m(0.5);
  m.set_width(width);
  m.set_height(static_cast<uint32_t>(cells.size()) / width);
  m.set_log_odds_scale(32);
  uLongf size = compressBound(static_cast<uLong>(cells.size()));
  std::string packed(size, '\0');
  compress2(reinterpret_cast<Bytef*>(packed.data()), &size,
            reinterpret_cast<const Bytef*>(cells.data()), static_cast<uLong>(cells.size()), 1);
  packed.resize(size);
  m.set_log_odds_zlib(packed);
  return m;
}

TEST(DashboardExploredTest, TheTeamsMapIsEveryWearersGridSummedNorthUp) {
  DashboardState state({});
  const auto t0 = Clock::now();
  std::string error;
  // Row 0 is the southern row (y from origin_y upwards).
  v1::ExploredMap a = Explored("lab", {-64, -64, 0, 0, 0, 0, 0, 64});
  auto* room = a.add_visited();
  room->set_id(2);
  room->set_x(1.5);
  room->set_y(0.25);
  ASSERT_TRUE(state.OnExplored("hl-a", a, t0, &error)) << error;
  v1::ExploredMap b = Explored("lab", {0, 0, -64, 0, 0, 0, 0, 0});
  *b.add_visited() = *room;
  ASSERT_TRUE(state.OnExplored("hl-b", b, t0, &error)) << error;
  // Another grid of the same plan (another cell layout) is left out, not mixed in.
  ASSERT_TRUE(state.OnExplored("hl-z", Explored("lab", {-64, -64, -64, -64, -64, -64}, 3, 7.0), t0,
                               &error));
  // A corrupt one is refused with the reason.
  v1::ExploredMap corrupt = Explored("lab", {0, 0, 0, 0, 0, 0, 0, 0});
  corrupt.set_log_odds_zlib("not zlib");
  EXPECT_FALSE(state.OnExplored("hl-c", corrupt, t0, &error));
  EXPECT_NE(error.find("do not unpack"), std::string::npos) << error;

  const std::string png = state.ExploredPng("lab");
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_memory(&image, png.data(), png.size()));
  image.format = PNG_FORMAT_RGBA;
  std::vector<unsigned char> px(PNG_IMAGE_SIZE(image));
  ASSERT_TRUE(png_image_finish_read(&image, nullptr, px.data(), 0, nullptr));
  ASSERT_EQ(image.width, 4u);
  ASSERT_EQ(image.height, 2u);
  auto alpha = [&](int x, int row_from_top) { return px[(row_from_top * 4 + x) * 4 + 3]; };
  auto blue = [&](int x, int row_from_top) { return px[(row_from_top * 4 + x) * 4 + 2]; };
  // Southern row (the image's bottom): free from Alice, free from Bob, unknown.
  EXPECT_GT(alpha(0, 1), 0);
  EXPECT_EQ(blue(0, 1), 244);
  EXPECT_GT(alpha(2, 1), 0);
  EXPECT_EQ(alpha(3, 1), 0);
  // Northern row: Alice saw a wall in its last cell.
  EXPECT_EQ(blue(3, 0), 160);
  EXPECT_GT(alpha(3, 0), alpha(0, 1));
  EXPECT_EQ(alpha(0, 0), 0);
  EXPECT_TRUE(state.ExploredPng("another-plan").empty());

  DashboardState::Cursor c;
  const json f = FrameOf(state, &c, t0);
  const json& lab = f["explored"]["lab"];
  EXPECT_EQ(lab["devices"], 2);
  EXPECT_EQ(lab["width"], 4);
  EXPECT_EQ(lab["origin"], json::parse("[-1.0, -1.0]"));
  EXPECT_EQ(lab["visited"], json::parse("[[1.5, 0.25]]"));    // one room, entered by both
  EXPECT_FALSE(FrameOf(state, &c, t0).contains("explored"));  // sent once until it changes
}

TEST(DashboardPlansTest, ListsEveryPlanWithItsBoundsAndWalls) {
  const FloorPlanParse plan = platform::ParseGeoJsonFloorPlan(
      R"({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {},
          "geometry": {"type": "LineString", "coordinates": [[0, 0], [4, 0], [4, 3]]}},
          {"type": "Feature", "properties": {"kind": "door"},
          "geometry": {"type": "LineString", "coordinates": [[1, 0], [2, 0]]}},
          {"type": "Feature", "properties": {"kind": "window"},
          "geometry": {"type": "LineString", "coordinates": [[0, 3], [4, 3]]}}]})",
      "lab");
  ASSERT_TRUE(plan.ok()) << plan.error;
  const json plans = json::parse(PlansJson({{plan.plan, "", "", 0.0, std::nullopt}}));
  ASSERT_EQ(plans["plans"].size(), 1u);
  EXPECT_EQ(plans["plans"][0]["id"], "lab");
  EXPECT_EQ(plans["plans"][0]["max"], json::parse("[4.0, 3.0]"));
  // The south wall less the door, and the east wall; the door and the window by kind.
  EXPECT_EQ(plans["plans"][0]["walls"].size(), 3u);
  EXPECT_EQ(plans["plans"][0]["lines"]["door"], json::parse("[[1.0, 0.0, 2.0, 0.0]]"));
  EXPECT_EQ(plans["plans"][0]["lines"]["window"].size(), 1u);
}

// North on a georeferenced plan: counter-clockwise from the plan's +x.
TEST(DashboardPlansTest, AGeoreferencedPlanSaysWhereNorthIs) {
  const FloorPlan plan = MakeFloorPlan("p", {{{0, 0}, {1, 0}}}).plan;
  Georeference turned;
  turned.rotation_rad = M_PI / 6;  // +x 30 degrees north of east: north 60 degrees from +x
  const json plans =
      json::parse(PlansJson({{plan, "", "", 0.0, turned}, {plan, "", "", 0.0, std::nullopt}}));
  EXPECT_NEAR(plans["plans"][0]["north_rad"].get<double>(), M_PI / 3, 1e-4);
  EXPECT_FALSE(plans["plans"][1].contains("north_rad"));
}

// The server: DDS in, HTTP out, on loopback.
TEST(DashboardServerTest, ServesThePageThePlansAndTheEventStreamOfWhatDdsCarries) {
  DashboardServerOptions o;
  o.domain_id = testing::UniqueDomain();
  o.cyclone_config = platform::LoopbackCycloneConfig();
  o.host = "127.0.0.1";
  o.port = 0;
  const FloorPlanParse plan = platform::ParseGeoJsonFloorPlan(
      R"({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {},
          "geometry": {"type": "LineString", "coordinates": [[0, 0], [4, 0]]}}]})",
      "lab");
  Dashboard dashboard(o, {{plan.plan, "", "", 0.0, std::nullopt}});
  std::thread server([&] { dashboard.Serve(); });

  platform::Participant daemon(o.domain_id, o.cyclone_config);
  platform::Writer poses(daemon, platform::Topic::kPlanPose);
  const auto deadline = Clock::now() + seconds(10);
  while (poses.MatchedReaders() == 0 && Clock::now() < deadline)
    std::this_thread::sleep_for(milliseconds(20));
  ASSERT_GT(poses.MatchedReaders(), 0);
  platform::Envelope e{"hl-a", poses.NextSeq(), 1, Pose(1.5, 2.5, 1).SerializeAsString(), 0};
  ASSERT_TRUE(poses.Write(e));
  platform::Envelope junk{"hl-junk", poses.NextSeq(), 2, "\xff\xff\xff not protobuf", 0};
  ASSERT_TRUE(poses.Write(junk));

  httplib::Client http("127.0.0.1", dashboard.port());
  json devices;
  for (int i = 0; i < 100; ++i) {
    auto r = http.Get("/api/devices");
    ASSERT_TRUE(r);
    devices = json::parse(r->body);
    if (!devices["devices"].empty()) break;
    std::this_thread::sleep_for(milliseconds(50));
  }
  ASSERT_EQ(devices["devices"].size(), 1u) << devices.dump();  // the junk made no device
  EXPECT_EQ(devices["devices"][0]["pose"]["y"], 2.5);

  auto page = http.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("/dashboard.js"), std::string::npos);
  EXPECT_EQ(page->get_header_value("Content-Type"), "text/html; charset=utf-8");
  for (const char* asset : {"/dashboard.js", "/dashboard.css"}) {
    auto r = http.Get(asset);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << asset;
    EXPECT_GT(r->body.size(), 100u) << asset;
  }
  auto plans = http.Get("/api/plans");
  ASSERT_TRUE(plans);
  EXPECT_EQ(json::parse(plans->body)["plans"][0]["id"], "lab");
  EXPECT_EQ(http.Get("/nothing-here")->status, 404);

  // The event stream: the whole picture first.
  std::string stream;
  auto events = http.Get("/events", [&](const char* data, size_t n) {
    stream.append(data, n);
    return stream.find("\n\n") == std::string::npos;
  });
  ASSERT_EQ(stream.rfind("data: ", 0), 0u) << stream;
  const json first = json::parse(stream.substr(6, stream.find("\n\n") - 6));
  ASSERT_EQ(first["devices"].size(), 1u);
  EXPECT_EQ(first["devices"][0]["id"], "hl-a");

  dashboard.Stop();
  server.join();
}

// What a lead does over HTTP goes out on DDS: markers (keyed by their id), their removal,
// and acknowledgements as commands to the wearer's daemon; a room searched is drawn.
TEST(DashboardServerTest, TheLeadsMarkersAndAcknowledgementsGoOutOnDds) {
  DashboardServerOptions o;
  o.domain_id = testing::UniqueDomain();
  o.cyclone_config = platform::LoopbackCycloneConfig();
  o.host = "127.0.0.1";
  o.port = 0;
  o.name = "chief";
  // Two rooms of 3 m x 4 m with a 0.9 m door between them.
  const FloorPlanParse plan = platform::ParseGeoJsonFloorPlan(
      R"({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": {"type": "Polygon",
         "coordinates": [[[0, 0], [6, 0], [6, 4], [0, 4], [0, 0]]]}},
        {"type": "Feature", "properties": {}, "geometry": {"type": "MultiLineString",
         "coordinates": [[[3, 0], [3, 1.5]], [[3, 2.4], [3, 4]]]}}]})",
      "two");
  ASSERT_TRUE(plan.ok()) << plan.error;
  Dashboard dashboard(o, {{plan.plan, "", "", 0.0, std::nullopt}});
  std::thread server([&] { dashboard.Serve(); });
  platform::Participant peer(o.domain_id, o.cyclone_config);
  platform::Reader markers(peer, platform::Topic::kMarker);
  platform::Reader commands(peer, platform::Topic::kCommand);
  const auto deadline = Clock::now() + seconds(10);
  while ((markers.MatchedWriters() == 0 || commands.MatchedWriters() == 0) &&
         Clock::now() < deadline)
    std::this_thread::sleep_for(milliseconds(20));
  ASSERT_GT(markers.MatchedWriters(), 0);
  // Takes what the peer heard on one topic, waiting for at least n samples.
  auto take = [&](platform::Reader& reader, size_t n) {
    std::vector<platform::Envelope> got;
    for (int i = 0; i < 200 && got.size() < n; ++i) {
      for (auto& e : reader.Take()) got.push_back(std::move(e));
      std::this_thread::sleep_for(milliseconds(20));
    }
    return got;
  };

  httplib::Client http("127.0.0.1", dashboard.port());
  EXPECT_EQ(http.Get("/api/searched/two.png")->status, 404) << "nothing searched yet";
  for (const char* bad :
       {"not json", R"({"kind": "dragon", "x": 1, "y": 1})",
        R"({"kind": "hazard", "x": "one", "y": 1})", R"({"id": "nobody", "removed": true})"}) {
    auto r = http.Post("/api/markers", bad, "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << bad;
    EXPECT_TRUE(json::parse(r->body).contains("error")) << r->body;
  }
  auto placed = http.Post("/api/markers",
                          R"({"kind": "searched", "plan": "two", "floor": "0", "x": 1, "y": 1})",
                          "application/json");
  ASSERT_TRUE(placed);
  ASSERT_EQ(placed->status, 200) << placed->body;
  const std::string id = json::parse(placed->body)["id"];
  EXPECT_EQ(id.rfind("chief-", 0), 0u) << id;
  std::vector<platform::Envelope> heard = take(markers, 1);
  ASSERT_GE(heard.size(), 1u);
  EXPECT_EQ(heard[0].device_id, id) << "keyed by the marker's id";
  v1::Marker m;
  ASSERT_TRUE(m.ParseFromString(heard[0].payload));
  EXPECT_EQ(m.kind(), v1::Marker::SEARCHED);
  EXPECT_EQ(m.author(), "chief");
  EXPECT_EQ(m.revision(), 1u);

  // The west room is drawn searched: its cells green, the east room's not.
  auto png = http.Get("/api/searched/two.png");
  ASSERT_TRUE(png);
  ASSERT_EQ(png->status, 200);
  EXPECT_EQ(png->body.substr(1, 3), "PNG");
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_memory(&image, png->body.data(), png->body.size()));
  image.format = PNG_FORMAT_RGBA;
  std::vector<unsigned char> rgba(PNG_IMAGE_SIZE(image));
  ASSERT_TRUE(png_image_finish_read(&image, nullptr, rgba.data(), 0, nullptr));
  const json grid = json::parse(http.Get("/api/plans")->body)["plans"][0]["rooms_grid"];
  auto alpha = [&](double x, double y) {  // the PNG is north up
    const int cx =
        static_cast<int>((x - grid["origin"][0].get<double>()) / grid["cell_m"].get<double>());
    const int cy =
        static_cast<int>((y - grid["origin"][1].get<double>()) / grid["cell_m"].get<double>());
    return rgba[(static_cast<size_t>(image.height - 1 - cy) * image.width + cx) * 4 + 3];
  };
  EXPECT_GT(alpha(1.5, 2.0), 0) << "the west room";
  EXPECT_EQ(alpha(4.5, 2.0), 0) << "the east room";

  auto removed =
      http.Post("/api/markers", json{{"id", id}, {"removed", true}}.dump(), "application/json");
  ASSERT_TRUE(removed);
  EXPECT_EQ(removed->status, 200) << removed->body;
  heard = take(markers, 1);
  ASSERT_GE(heard.size(), 1u);
  ASSERT_TRUE(m.ParseFromString(heard.back().payload));
  EXPECT_TRUE(m.removed());
  EXPECT_EQ(m.revision(), 2u);
  EXPECT_EQ(http.Get("/api/searched/two.png")->status, 404);

  auto ack = http.Post("/api/alerts/ack", R"({"device": "hl-07"})", "application/json");
  ASSERT_TRUE(ack);
  EXPECT_EQ(ack->status, 202);
  heard = take(commands, 1);
  ASSERT_EQ(heard.size(), 1u);
  EXPECT_EQ(heard[0].device_id, "hl-07") << "to the wearer's daemon";
  v1::Command cmd;
  ASSERT_TRUE(cmd.ParseFromString(heard[0].payload));
  EXPECT_EQ(cmd.acknowledge_alert().by(), "chief");
  EXPECT_EQ(http.Post("/api/alerts/ack", "{}", "application/json")->status, 400);

  dashboard.Stop();
  server.join();
}

}  // namespace
}  // namespace floorpose::tools
