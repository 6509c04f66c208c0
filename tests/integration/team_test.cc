// What floorposed does for the team, tried as the AR app and a second wearer would, over
// real DDS with real daemon processes: the way out and the way back round a blocked
// marker, the teammates query, and the no-motion alert and its acknowledgement.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "platform/floor_plan_io.h"
#include "tests/integration/daemon_fixture.h"
#include "tests/route_test_util.h"
// After Eigen: httplib.h includes glibc's <resolv.h>, which defines _res, a name in Eigen.
#include <httplib.h>

#include "tools/lib/dashboard.h"

namespace floorpose {
namespace {

using std::chrono::seconds;

class TeamTest : public DaemonTest {
 protected:
  // The demo office (a developer plan of eval-suite) instead of the fixture's room.
  void UseOffice() {
    plan_path_ = (dir_ / "office.geojson").string();
    fs::copy_file(FLOORPOSE_DEMO_PLAN, plan_path_, fs::copy_options::overwrite_existing);
  }
  // In at the entrance, into a south room and out, along the corridor, into a north room
  // and out, to the corridor's east end.
  static sim::DemoWalk OfficeWalk(const FloorPlan& plan) {
    sim::DemoWalkOptions o;
    o.seed = 7;
    o.heading_drift_rad_per_m = 0;
    o.scale_error = 0;
    o.initial_theta_rad = 0.4;
    o.initial_offset_m = {1.0, -2.0};
    o.pick_point_error_m = 0;
    o.pick_normal_error_rad = 0;
    return sim::SimulateDemoWalk(plan,
                                 {{1.2, 7.0},
                                  {8.05, 7.0},
                                  {8.05, 4.0},
                                  {8.05, 7.0},
                                  {20.45, 7.0},
                                  {20.45, 10.5},
                                  {20.45, 7.0},
                                  {26.0, 7.0}},
                                 o);
  }
  // Publishes a marker as the team lead's dashboard does: its own participant, the
  // marker topic keyed by the marker id.
  void PlaceAsLead(const v1::Marker& marker) {
    if (!lead_) {
      lead_ = std::make_unique<platform::Participant>(domain_, platform::LoopbackCycloneConfig());
      lead_writer_ = std::make_unique<platform::Writer>(*lead_, Topic::kMarker);
    }
    platform::Envelope e;
    e.device_id = marker.id();
    e.seq = lead_writer_->NextSeq();
    marker.SerializeToString(&e.payload);
    ASSERT_TRUE(lead_writer_->Write(e));
  }
  std::unique_ptr<platform::Participant> lead_;
  std::unique_ptr<platform::Writer> lead_writer_;
};

double ClosestTo(const v1::RouteReply& r, const Eigen::Vector2d& c) {
  double closest = INFINITY;
  for (int i = 1; i < r.path_size(); ++i) {
    const Segment leg{{r.path(i - 1).x(), r.path(i - 1).y()}, {r.path(i).x(), r.path(i).y()}};
    closest = std::min(closest, (ClosestPointOnSegment(leg, c) - c).norm());
  }
  return closest;
}

std::vector<Eigen::Vector2d> Path(const v1::RouteReply& r) {
  std::vector<Eigen::Vector2d> path;
  for (const auto& p : r.path()) path.push_back({p.x(), p.y()});
  return path;
}

TEST_F(TeamTest, TheWayOutAndTheWayBackKeepClearOfWallsAndOfABlockedMarker) {
  UseOffice();
  // Deterministic: the walk ends RELIABLE however loaded the machine is (the belief's
  // updates are applied before the next pose, as `floorpose eval` does).
  StartDaemon("deterministic: true\n");
  const FloorPlanParse plan = platform::LoadFloorPlan(plan_path_);
  ASSERT_TRUE(plan.ok()) << plan.error;
  const sim::DemoWalk walk = OfficeWalk(plan.plan);
  ASSERT_NO_FATAL_FAILURE(PickAndWalk(walk));
  const v1::PlanPose last = link_->plan_poses.back();
  ASSERT_EQ(last.reliability().flag(), v1::Reliability::RELIABLE) << last.ShortDebugString();
  const double body = 0.3;  // routes.body_radius_m

  // The wearer marks a victim where the headset is: it lands where the wearer is, under
  // the alignment in use when it is placed (an update that ends after the last pose moves
  // it by millimetres from the last pose published).
  v1::Command place;
  place.mutable_place_marker()->set_kind(v1::Marker::VICTIM);
  place.mutable_place_marker()->set_text("conscious");
  *place.mutable_place_marker()->mutable_headset_point() =
      tools::ToHeadsetPose(walk.steps.back().slam, kFrame, 0).position();
  const auto placed = link_->Request(place, seconds(5));
  ASSERT_TRUE(placed && placed->ok()) << (placed ? placed->message() : "no reply");
  EXPECT_NEAR(placed->marker().x(), last.x(), 0.05);
  EXPECT_NEAR(placed->marker().y(), last.y(), 0.05);
  EXPECT_EQ(placed->marker().plan_id(), "office");
  EXPECT_EQ(placed->marker().author(), "hl-test");
  EXPECT_EQ(placed->marker().placed_from().flag(), v1::Reliability::RELIABLE);

  auto request = [&](v1::Command::Route::Destination to) {
    v1::Command c;
    c.mutable_route()->set_destination(to);
    auto reply = link_->Request(c, seconds(5));
    EXPECT_TRUE(reply.has_value());
    return reply.value_or(v1::CommandReply{});
  };
  // The way out: the office's one exit, the entrance at its west end.
  const v1::CommandReply out = request(v1::Command::Route::EXIT);
  ASSERT_TRUE(out.ok()) << out.message();
  ASSERT_GE(out.route().path_size(), 2) << out.ShortDebugString();
  const auto& exit_end = out.route().path(out.route().path_size() - 1);
  EXPECT_LT(exit_end.x(), 1.2) << out.route().ShortDebugString();
  EXPECT_NEAR(exit_end.y(), 7.0, 0.6);
  EXPECT_GE(testing::PathClearance(Path(out.route()), plan.plan.segments), body - 1e-9);
  // The way back: where the walk began (the alignment's error apart).
  const v1::CommandReply back = request(v1::Command::Route::BACKTRACK);
  ASSERT_TRUE(back.ok()) << back.message();
  const auto& back_end = back.route().path(back.route().path_size() - 1);
  EXPECT_LT(std::hypot(back_end.x() - 1.2, back_end.y() - 7.0), 0.5)
      << back.route().ShortDebugString();
  EXPECT_GE(testing::PathClearance(Path(back.route()), plan.plan.segments), body - 1e-9);

  // A destination this daemon does not know (a newer app): refused, not routed to (0, 0).
  const v1::CommandReply unknown = request(static_cast<v1::Command::Route::Destination>(7));
  EXPECT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.message(), "unknown route destination 7");

  // The lead marks a hazard in the corridor: both go round it, clear of it by the body.
  const Eigen::Vector2d hazard(12.0, 6.5);
  v1::Marker m;
  m.set_id("lead-hazard-1");
  m.set_kind(v1::Marker::BLOCKED);
  m.set_plan_id("office");
  m.set_floor(last.floor());
  m.set_x(hazard.x());
  m.set_y(hazard.y());
  m.set_radius_m(0.5);
  m.set_revision(1);
  m.set_author("lead");
  ASSERT_NO_FATAL_FAILURE(PlaceAsLead(m));
  // The daemon holds it once it re-publishes it (it keeps every marker for late joiners).
  platform::Reader markers(*lead_, Topic::kMarker);
  // The reader also hears the markers the daemon kept from before (the victim's), so
  // only copies of this one count.
  size_t heard = 0;
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        for (const platform::Envelope& e : markers.Take()) {
          v1::Marker copy;
          heard += copy.ParseFromString(e.payload) && copy.id() == m.id();
        }
        return heard >= 2;  // the lead's own and the daemon's copy
      },
      seconds(10)))
      << heard << " copies";
  for (const auto& [to, name] : {std::pair{v1::Command::Route::EXIT, "exit"},
                                 std::pair{v1::Command::Route::BACKTRACK, "backtrack"}}) {
    SCOPED_TRACE(name);
    const v1::CommandReply r = request(to);
    ASSERT_TRUE(r.ok()) << r.message();
    EXPECT_GE(ClosestTo(r.route(), hazard), 0.5 + body - 1e-9) << r.route().ShortDebugString();
    EXPECT_GE(testing::PathClearance(Path(r.route()), plan.plan.segments), body - 1e-9);
    EXPECT_LT(r.route().path(r.route().path_size() - 1).x(), 1.7);
  }
  // Across the whole corridor: no way out, and the reply says why.
  m.set_revision(2);
  m.set_radius_m(1.2);
  m.set_y(7.0);
  ASSERT_NO_FATAL_FAILURE(PlaceAsLead(m));
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        const v1::CommandReply r = request(v1::Command::Route::EXIT);
        return !r.ok() && r.message().find("blocked") != std::string::npos;
      },
      seconds(10)));
}

TEST_F(TeamTest, TheTeammatesQueryReturnsBothWearers) {
  StartDaemon("deterministic: true\n");
  // A second wearer with a daemon of its own on the same domain.
  const std::string second_config =
      WriteConfig("hl-second", "deterministic: true\n", "second.conf");
  tools::ChildProcess second({FLOORPOSED_PATH, "--config", second_config},
                             (dir_ / "second.log").string());
  ASSERT_TRUE(second.started());
  tools::HeadsetLink second_link(domain_, platform::LoopbackCycloneConfig(), "hl-second");
  ASSERT_TRUE(second_link.WaitForDaemon(seconds(15)));
  ASSERT_NO_FATAL_FAILURE(PickAndWalk(Walk(0.0, 5)));
  ASSERT_NO_FATAL_FAILURE(PickAndWalk(Walk(0.0, 6), second_link));
  v1::Command ask;
  ask.mutable_get_teammates();
  std::optional<v1::CommandReply> reply;
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        reply = link_->Request(ask, seconds(5));
        if (!reply || reply->teammates_size() != 2) return false;
        // The daemon takes the team's poses in its own time: until it has both last ones.
        for (const v1::Teammate& t : reply->teammates()) {
          const tools::HeadsetLink& own = t.device_id() == "hl-test" ? *link_ : second_link;
          if (t.pose().source_stamp_ns() != own.plan_poses.back().source_stamp_ns()) return false;
        }
        return true;
      },
      seconds(10)))
      << (reply ? reply->ShortDebugString().substr(0, 400) : "no reply");
  EXPECT_TRUE(reply->ok());
  EXPECT_EQ(reply->command(), "get_teammates");
  for (const v1::Teammate& t : reply->teammates()) {
    SCOPED_TRACE(t.device_id());
    const tools::HeadsetLink& own = t.device_id() == "hl-test" ? *link_ : second_link;
    ASSERT_EQ(t.device_id(), own.device_id());
    const v1::PlanPose& want = own.plan_poses.back();
    EXPECT_EQ(t.pose().source_stamp_ns(), want.source_stamp_ns());
    EXPECT_DOUBLE_EQ(t.pose().x(), want.x());
    EXPECT_DOUBLE_EQ(t.pose().y(), want.y());
    EXPECT_EQ(t.plan_id(), "room");
    EXPECT_TRUE(t.state() == v1::DaemonStatus::TRACKING || t.state() == v1::DaemonStatus::DEGRADED)
        << v1::DaemonStatus::State_Name(t.state());
    EXPECT_LT(t.pose_age_s(), 10.0);
  }
  EXPECT_EQ(second.Terminate(seconds(2)), 0);
}

TEST_F(TeamTest, AWearerWhoStopsMovingIsInAlertUntilAcknowledgedAndMovesOn) {
  StartDaemon("alerts { no_motion_s: 3 pre_alert_s: 2 }\n");
  // An outsider on the alert topic, as a dashboard joins it.
  platform::Participant watcher(domain_, platform::LoopbackCycloneConfig());
  platform::Reader alerts(watcher, Topic::kAlert);
  ASSERT_TRUE(link_->WaitUntil([&] { return alerts.MatchedWriters() > 0; }, seconds(10)));
  std::vector<v1::Alert> heard;
  auto listen = [&] {
    for (const platform::Envelope& e : alerts.Take()) {
      v1::Alert a;
      ASSERT_TRUE(a.ParseFromString(e.payload));
      EXPECT_EQ(e.device_id, "hl-test");
      heard.push_back(a);
    }
  };
  const Pose2 still{{2.0, 3.0}, 0.4, 1.6};
  int64_t stamp = 1'000'000'000;
  auto pose_at = [&](const Pose2& p) {
    stamp += 300'000'000;
    link_->Send(Topic::kHeadsetPose, tools::ToHeadsetPose(p, kFrame, stamp), stamp);
  };
  // 3.6 s of headset time, paced so that the watcher hears each alert (the topic keeps
  // the latest of a device).
  for (int i = 0; i < 12; ++i) {
    pose_at(still);
    link_->WaitUntil([] { return false; }, std::chrono::milliseconds(60));
  }
  ASSERT_TRUE(WaitForStatus([](const v1::DaemonStatus& s) {
    return s.alert().kind() == v1::Alert::NO_MOTION;
  })) << link_->status->alert().ShortDebugString();
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        listen();
        return !heard.empty() && heard.back().kind() == v1::Alert::NO_MOTION;
      },
      seconds(5)));
  ASSERT_GE(heard.size(), 2u);
  EXPECT_EQ(heard[heard.size() - 2].kind(), v1::Alert::PRE_ALERT) << "the pre-alert came first";
  EXPECT_GE(heard.back().still_s(), 3.0);

  v1::Command ack;
  ack.mutable_acknowledge_alert()->set_by("lead");
  const auto acked = link_->Request(ack, seconds(5));
  ASSERT_TRUE(acked && acked->ok()) << (acked ? acked->message() : "no reply");
  EXPECT_TRUE(acked->status().alert().acknowledged());
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        listen();
        return heard.back().acknowledged() && heard.back().acknowledged_by() == "lead";
      },
      seconds(5)));
  // A step: the episode is over.
  pose_at({{2.6, 3.0}, 0.4, 1.6});
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        listen();
        return heard.back().kind() == v1::Alert::NONE;
      },
      seconds(5)));
  EXPECT_FALSE(heard.back().acknowledged());
  const auto again = link_->Request(ack, seconds(5));
  ASSERT_TRUE(again.has_value());
  EXPECT_FALSE(again->ok());
  EXPECT_EQ(again->message(), "no alert to acknowledge");
}

TEST_F(TeamTest, AMarkerOutlivesItsAuthorAndADaemonRestart) {
  StartDaemon("state_dir: \"" + (dir_ / "state").string() + "\"\n");
  v1::Marker m;
  m.set_id("lead-blocked-7");
  m.set_kind(v1::Marker::BLOCKED);
  m.set_plan_id("room");
  m.set_floor("0");
  m.set_x(9.0);
  m.set_y(1.0);
  m.set_revision(1);
  m.set_author("lead");
  ASSERT_NO_FATAL_FAILURE(PlaceAsLead(m));
  // The daemon heard it and keeps it: a copy of its own is on the topic.
  {
    platform::Reader markers(*lead_, Topic::kMarker);
    size_t copies = 0;
    ASSERT_TRUE(link_->WaitUntil(
        [&] {
          copies += markers.Take().size();
          return copies >= 2;
        },
        seconds(10)));
  }
  // The lead's dashboard goes away, then the daemon restarts.
  lead_writer_.reset();
  lead_.reset();
  ASSERT_EQ(daemon_->Terminate(seconds(5)), 0);
  LaunchDaemon();
  ASSERT_TRUE(link_->WaitForDaemon(seconds(15)));
  // A newcomer gets the marker from the restarted daemon, the only one left holding it.
  platform::Participant newcomer(domain_, platform::LoopbackCycloneConfig());
  platform::Reader markers(newcomer, Topic::kMarker);
  std::vector<platform::Envelope> heard;
  ASSERT_TRUE(link_->WaitUntil(
      [&] {
        for (auto& e : markers.Take()) heard.push_back(std::move(e));
        return !heard.empty();
      },
      seconds(10)))
      << "the restarted daemon did not publish the marker; log " << log_path_;
  EXPECT_EQ(heard[0].device_id, "lead-blocked-7");
  v1::Marker got;
  ASSERT_TRUE(got.ParseFromString(heard[0].payload));
  EXPECT_EQ(got.kind(), v1::Marker::BLOCKED);
  EXPECT_EQ(got.author(), "lead");
  EXPECT_NE(Log().find("1 markers from"), std::string::npos) << Log();
}

TEST_F(TeamTest, ARestartedDeviceReappearsOnTheDashboard) {
  StartDaemon();
  const fs::path log = dir_ / "dashboard.log";
  tools::ChildProcess dashboard(
      {FLOORPOSE_PATH, "dashboard", "--plan", plan_path_, "--host", "127.0.0.1", "--port", "0",
       "--domain", std::to_string(domain_), "--loopback", "--stale-after", "2"},
      log.string());
  const int port = tools::DashboardPortFromLog(log.string(), seconds(15));
  ASSERT_GT(port, 0) << "see " << log;
  httplib::Client http("127.0.0.1", port);
  // The device as the dashboard serves it (GET /api/devices), when pred holds.
  auto device = [&](auto pred) {
    nlohmann::json found;
    link_->WaitUntil(
        [&] {
          const auto r = http.Get("/api/devices");
          if (!r || r->status != 200) return false;
          const nlohmann::json frame = nlohmann::json::parse(r->body);
          for (const auto& d : frame["devices"])
            if (d["id"] == "hl-test") {
              found = d;
              found["age"] = frame["ages"]["hl-test"];
            }
          return !found.is_null() && pred(found);
        },
        seconds(10));
    return found;
  };
  auto near = [](const nlohmann::json& d, const v1::PlanPose& p) {
    return d.contains("pose") && std::abs(d["pose"]["x"].get<double>() - p.x()) < 0.002 &&
           std::abs(d["pose"]["y"].get<double>() - p.y()) < 0.002;
  };
  ASSERT_NO_FATAL_FAILURE(PickAndWalk(Walk(0.0, 5)));
  const v1::PlanPose before = link_->plan_poses.back();
  nlohmann::json d = device([&](const nlohmann::json& shown) { return near(shown, before); });
  ASSERT_TRUE(near(d, before)) << d.dump();

  // The daemon dies and comes back; the headset's app restarts too, its stamps from the
  // start again, the wearer elsewhere.
  ASSERT_EQ(daemon_->Terminate(seconds(5)), 0);
  d = device([](const nlohmann::json& shown) { return shown["age"].get<double>() > 2.0; });
  EXPECT_GT(d["age"].get<double>(), 2.0) << "stale while the daemon is gone";
  LaunchDaemon();
  ASSERT_TRUE(link_->WaitForDaemon(seconds(15))) << "floorposed did not come back";
  link_->plan_poses.clear();
  link_->alignments.clear();
  ASSERT_NO_FATAL_FAILURE(PickAndWalk(Walk(0.0, 6, {{8.8, 2.0}, {6.0, 4.8}, {2.5, 4.8}})));
  const v1::PlanPose after = link_->plan_poses.back();
  ASSERT_LT(after.source_stamp_ns(), before.source_stamp_ns()) << "the stamps started again";
  // ...where the restarted daemon put it, fresh, in the state that daemon reports.
  d = device([&](const nlohmann::json& shown) {
    return near(shown, after) && link_->status &&
           shown["state"] == v1::DaemonStatus::State_Name(link_->status->state());
  });
  EXPECT_TRUE(near(d, after)) << d.dump();
  EXPECT_LT(d["age"].get<double>(), 2.0);
  EXPECT_EQ(d["state"], v1::DaemonStatus::State_Name(link_->status->state()));
  EXPECT_EQ(dashboard.Terminate(seconds(5)), 0);
}

}  // namespace
}  // namespace floorpose
