// Bad input at the daemon's boundary: every kind of refusal is counted in DaemonStatus
// by its reason, nothing crashes, and the good data around it is kept (the cases of
// docs/robustness.md).
#include <gtest/gtest.h>

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

#include "platform/engine.h"
#include "tests/test_util.h"

namespace floorpose::platform {
namespace {

class EngineInputTest : public testing::TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    config_.mutable_dds()->set_device_id("hl-1");
    config_.set_headset_frame("zup");
    config_.mutable_limits()->set_max_vertices_per_mesh(1000);
  }
  void Start(bool with_plan) {
    if (with_plan) config_.set_plan_path(Write("room.txt", "1\n0 0 10 0\n"));
    engine_ = std::make_unique<Engine>(
        config_,
        [this](Topic topic, const google::protobuf::Message& m) {
          if (topic == Topic::kPlanPose) poses_.push_back(static_cast<const v1::PlanPose&>(m));
        },
        [this] { return clock_ns_; });
    engine_->Start();
  }
  static Envelope Wrap(const google::protobuf::Message& m) {
    Envelope e;
    e.device_id = "hl-1";
    m.SerializeToString(&e.payload);
    return e;
  }
  static Envelope Raw(std::string bytes) {
    Envelope e;
    e.device_id = "hl-1";
    e.payload = std::move(bytes);
    return e;
  }
  // A `length` x 2.5 m wall along x at y = 1 (zup frame), as two triangles.
  static v1::MeshDelta Wall(uint64_t id, v1::MeshDelta::Change change, int64_t stamp_ns,
                            float length = 4.f) {
    v1::MeshDelta m;
    m.set_mesh_id(id);
    m.set_change(change);
    m.set_stamp_ns(stamp_ns);
    for (float v : {0.f, 1.f, 0.f, length, 1.f, 0.f, length, 1.f, 2.5f, 0.f, 1.f, 2.5f})
      m.add_vertices(v);
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.add_triangles(i);
    return m;
  }
  static v1::HeadsetPose Pose(int64_t stamp_ns, double x = 1.0, double z = 1.6) {
    v1::HeadsetPose p;
    p.set_stamp_ns(stamp_ns);
    p.mutable_position()->set_x(x);
    p.mutable_position()->set_z(z);
    p.mutable_orientation()->set_w(1.0);
    return p;
  }
  // A pick of the Wall() below (headset y = 1, facing -y) on the plan wall y = 0 at x = 2.
  static v1::Command WallPickAtWall() {
    v1::Command pick;
    pick.set_request_id(1);
    v1::Command::WallPick* w = pick.mutable_wall_pick();
    w->mutable_headset_point()->set_x(2);
    w->mutable_headset_point()->set_y(1);
    w->mutable_headset_point()->set_z(1.5);
    w->mutable_headset_normal()->set_y(-1);
    w->set_plan_x(2);
    w->set_plan_normal_y(1);
    return pick;
  }
  const v1::DaemonStatus::Counters& c() const { return engine_->counters(); }
  // A 3 x 3 m room, where a 9 m Wall() fits nowhere: the belief stays empty, and a search
  // is due every recovery.search_interval_s.
  static constexpr const char* kSmallRoom = "4\n0 0 3 0\n3 0 3 3\n3 3 0 3\n0 3 0 0\n";

  v1::FloorposedConfig config_;
  std::unique_ptr<Engine> engine_;
  std::vector<v1::PlanPose> poses_;
  int64_t clock_ns_ = 0;
};

TEST_F(EngineInputTest, RefusalsAreCountedByReasonAndGoodDataIsKept) {
  Start(/*with_plan=*/true);
  engine_->OnMeshDelta(Wrap(Wall(1, v1::MeshDelta::ADDED, 10)));
  const size_t good_points = engine_->store().points();
  ASSERT_GT(good_points, 0u);

  engine_->OnMeshDelta(Raw("\xff\xff\xff not protobuf"));
  engine_->OnHeadsetPose(Raw("\x0a\x05\x08"));
  EXPECT_EQ(c().malformed(), 2u);

  v1::MeshDelta unknown = Wall(2, v1::MeshDelta::ADDED, 11);
  unknown.set_change(static_cast<v1::MeshDelta::Change>(99));
  engine_->OnMeshDelta(Wrap(unknown));
  v1::HeadsetPose tracking = Pose(12);
  tracking.set_tracking(static_cast<v1::HeadsetPose::TrackingState>(42));
  engine_->OnHeadsetPose(Wrap(tracking));
  EXPECT_EQ(c().unknown_enum_values(), 2u);

  v1::HeadsetPose nan = Pose(13);
  nan.mutable_position()->set_y(std::numeric_limits<double>::quiet_NaN());
  engine_->OnHeadsetPose(Wrap(nan));
  v1::MeshDelta inf = Wall(3, v1::MeshDelta::ADDED, 14);
  for (int i = 0; i < 16; ++i) inf.add_mesh_to_world(i % 5 == 0 ? 1.f : 0.f);
  inf.set_mesh_to_world(3, std::numeric_limits<float>::infinity());
  engine_->OnMeshDelta(Wrap(inf));
  EXPECT_EQ(c().non_finite(), 2u);

  engine_->OnHeadsetPose(Wrap(Pose(15, 1e7)));  // beyond 10 km
  v1::HeadsetPose squashed = Pose(16);
  squashed.mutable_orientation()->set_w(2.0);
  engine_->OnHeadsetPose(Wrap(squashed));
  engine_->OnHeadsetPose(Wrap(Pose(std::numeric_limits<int64_t>::max())));
  EXPECT_EQ(c().out_of_range(), 3u);

  v1::MeshDelta ragged = Wall(4, v1::MeshDelta::ADDED, 17);
  ragged.add_vertices(1.f);
  engine_->OnMeshDelta(Wrap(ragged));
  v1::MeshDelta affine = Wall(5, v1::MeshDelta::ADDED, 18);
  for (int i = 0; i < 16; ++i) affine.add_mesh_to_world(1.f);
  engine_->OnMeshDelta(Wrap(affine));
  EXPECT_EQ(c().inconsistent(), 2u);

  v1::MeshDelta huge = Wall(6, v1::MeshDelta::ADDED, 19);
  for (int i = 0; i < 3 * 1001; ++i) huge.add_vertices(0.f);
  engine_->OnMeshDelta(Wrap(huge));
  EXPECT_EQ(c().over_limits(), 1u);
  EXPECT_EQ(c().rejected_messages(), 12u);

  // Inside an accepted mesh: the bad triangles go, the good one stays.
  v1::MeshDelta holes = Wall(7, v1::MeshDelta::ADDED, 20);
  for (uint32_t i : {0u, 1u, 99u, 0u, 0u, 0u}) holes.add_triangles(i);
  engine_->OnMeshDelta(Wrap(holes));
  EXPECT_EQ(c().bad_index_triangles(), 1u);
  EXPECT_EQ(c().degenerate_triangles(), 1u);
  EXPECT_EQ(engine_->store().meshes(), 2u);

  // Order: an update older than the stored mesh is ignored; a late pose is answered but
  // not tracked; a repeated one is dropped.
  v1::MeshDelta late = Wall(1, v1::MeshDelta::UPDATED, 5);
  late.clear_triangles();
  engine_->OnMeshDelta(Wrap(late));
  EXPECT_EQ(c().stale_stamps(), 1u);
  EXPECT_EQ(engine_->store().MeshPoints(1), good_points);
  engine_->OnHeadsetPose(Wrap(Pose(100)));
  engine_->OnHeadsetPose(Wrap(Pose(100)));
  engine_->OnHeadsetPose(Wrap(Pose(50)));
  EXPECT_EQ(c().duplicate_stamps(), 1u);
  EXPECT_EQ(c().stale_stamps(), 2u);
  ASSERT_EQ(poses_.size(), 2u);
  EXPECT_EQ(poses_[1].source_stamp_ns(), 50);

  // UPDATED and REMOVED for ids never added: the update is kept, the removal ignored.
  engine_->OnMeshDelta(Wrap(Wall(8, v1::MeshDelta::UPDATED, 30)));
  v1::MeshDelta gone;
  gone.set_mesh_id(9);
  gone.set_change(v1::MeshDelta::REMOVED);
  engine_->OnMeshDelta(Wrap(gone));
  EXPECT_EQ(c().unknown_mesh_ids(), 2u);
  EXPECT_EQ(engine_->store().meshes(), 3u);
  EXPECT_EQ(engine_->store().MeshPoints(1), good_points);
}

TEST_F(EngineInputTest, PosesBeforeAPlanAndPlansThatAreNotPlans) {
  Start(/*with_plan=*/false);
  engine_->OnHeadsetPose(Wrap(Pose(1)));
  EXPECT_EQ(c().poses_without_plan(), 1u);
  ASSERT_EQ(poses_.size(), 1u);
  EXPECT_EQ(poses_[0].reliability().flag(), v1::Reliability::UNRELIABLE);

  for (const auto& [name, contents] :
       std::vector<std::pair<std::string, std::string>>{{"empty.geojson", ""},
                                                        {"zero.txt", "0\n"},
                                                        {"picture.geojson", "\x89PNG\r\n\x1a\n"},
                                                        {"lies.txt", "1000000000\n0 0 1 1\n"}}) {
    v1::Command load;
    load.set_request_id(1);
    load.mutable_load_plan()->set_path(Write(name, contents));
    engine_->OnCommand(Wrap(load));
  }
  EXPECT_EQ(c().plans_refused(), 4u);
  EXPECT_EQ(c().commands_refused(), 4u);
  EXPECT_FALSE(engine_->tracker().has_plan());
}

TEST_F(EngineInputTest, TheWallStoreIsBoundedByAreaNotTime) {
  Start(/*with_plan=*/true);
  // Re-scans of the same surface, again and again: they replace, never grow.
  engine_->OnMeshDelta(Wrap(Wall(1, v1::MeshDelta::ADDED, 10)));
  const size_t one_mesh = engine_->store().points();
  ASSERT_GT(one_mesh, 100u);
  for (int k = 1; k <= 500; ++k)
    engine_->OnMeshDelta(Wrap(Wall(1, v1::MeshDelta::UPDATED, 10 + k)));
  EXPECT_LE(engine_->store().points(), one_mesh * 11 / 10);  // each scan samples anew
  EXPECT_EQ(engine_->store().meshes(), 1u);
  EXPECT_EQ(c().meshes_updated(), 500u);

  // A cap of three meshes: the fourth and fifth new surfaces evict the oldest scans, and
  // an update keeps its mesh fresh.
  config_.mutable_limits()->set_max_wall_points(static_cast<uint32_t>(one_mesh * 3 + one_mesh / 2));
  Start(/*with_plan=*/true);
  for (uint64_t id = 1; id <= 3; ++id)
    engine_->OnMeshDelta(Wrap(Wall(id, v1::MeshDelta::ADDED, static_cast<int64_t>(id) * 10)));
  EXPECT_EQ(engine_->store().meshes(), 3u);
  engine_->OnMeshDelta(Wrap(Wall(1, v1::MeshDelta::UPDATED, 35)));  // 2 is now the oldest
  engine_->OnMeshDelta(Wrap(Wall(4, v1::MeshDelta::ADDED, 40)));
  EXPECT_FALSE(engine_->store().Contains(2));
  EXPECT_TRUE(engine_->store().Contains(1));
  engine_->OnMeshDelta(Wrap(Wall(5, v1::MeshDelta::ADDED, 50)));
  EXPECT_FALSE(engine_->store().Contains(3));
  EXPECT_EQ(engine_->store().meshes(), 3u);
  EXPECT_LE(engine_->store().points(), config_.limits().max_wall_points());
  EXPECT_EQ(c().meshes_evicted(), 2u);
  EXPECT_EQ(c().rejected_messages(), 0u);  // eviction is not a refusal
  for (uint64_t id : {1u, 4u, 5u}) EXPECT_TRUE(engine_->store().Contains(id)) << id;

  // One mesh over the whole cap is refused, and evicts nothing.
  config_.mutable_limits()->set_max_wall_points(static_cast<uint32_t>(one_mesh / 2));
  Start(/*with_plan=*/true);
  engine_->OnMeshDelta(Wrap(Wall(1, v1::MeshDelta::ADDED, 10)));
  EXPECT_EQ(c().over_limits(), 1u);
  EXPECT_EQ(engine_->store().points(), 0u);
}

TEST_F(EngineInputTest, AWheeledDeviceMovesTheBeliefWithTheWheelsDrift) {
  Start(/*with_plan=*/true);
  const double headset = engine_->tracker().options().motion.heading_rad_per_sqrt_m;
  v1::HeadsetPose wheel = Pose(1);
  wheel.set_odometry(v1::HeadsetPose::WHEEL);
  engine_->OnHeadsetPose(Wrap(wheel));
  EXPECT_GT(engine_->tracker().options().motion.heading_rad_per_sqrt_m, 10 * headset);
  EXPECT_LT(engine_->tracker().options().window_s, 20);
  engine_->OnHeadsetPose(Wrap(Pose(2)));  // unset again: a headset's SLAM
  EXPECT_EQ(engine_->tracker().options().motion.heading_rad_per_sqrt_m, headset);
  EXPECT_EQ(engine_->tracker().options().window_s, 20);
}

// The whole-plan search runs on new walls only: a search on the walls of the last one
// finds the same places again (issue 7).
TEST_F(EngineInputTest, TheSearchWaitsForNewWalls) {
  config_.set_plan_path(Write("small.txt", kSmallRoom));
  Start(/*with_plan=*/false);
  const int64_t s = 1'000'000'000;
  engine_->OnMeshDelta(Wrap(Wall(1, v1::MeshDelta::ADDED, 1 * s, 9.0)));
  engine_->OnHeadsetPose(Wrap(Pose(1 * s)));
  auto first = engine_->TakeDueJob();
  ASSERT_TRUE(first && first->global);
  engine_->OnRegistrationDone(RunJob(std::move(*first), [] { return int64_t{0}; }));
  ASSERT_FALSE(engine_->tracker().has_alignment());
  // The wearer stands; intervals pass with nothing new scanned: no search.
  for (int k = 2; k <= 10; ++k) {
    engine_->OnHeadsetPose(Wrap(Pose(k * s)));
    EXPECT_FALSE(engine_->TakeDueJob()) << k << " s";
  }
  // The wall is scanned again (its points sampled anew): searched again, within an
  // interval.
  engine_->OnMeshDelta(Wrap(Wall(1, v1::MeshDelta::UPDATED, 11 * s, 9.0)));
  std::optional<Job> second;
  for (int k = 11; k <= 14 && !second; ++k) {
    engine_->OnHeadsetPose(Wrap(Pose(k * s)));
    second = engine_->TakeDueJob();
  }
  ASSERT_TRUE(second && second->global);
}

// A search is due, but the walls of its window are too few (the store's are older): the
// look counts as a search, and the next comes a search interval later, on the walls of
// that interval too (docs/evaluation.md, Recovery).
TEST_F(EngineInputTest, ALookAtTooFewWallsCountsAsASearch) {
  config_.set_plan_path(Write("small.txt", kSmallRoom));
  Start(/*with_plan=*/false);
  const int64_t s = 1'000'000'000;
  engine_->OnMeshDelta(Wrap(Wall(1, v1::MeshDelta::ADDED, 1 * s, 9.0)));
  const tracking::MclOptions& options = engine_->tracker().options();
  ASSERT_GE(engine_->store().points(), options.search_min_points);
  // The wall is still in the store, but older than the search's window.
  const int64_t later = static_cast<int64_t>((options.search_window_s + 2) * 1e9);
  clock_ns_ = later;
  engine_->OnHeadsetPose(Wrap(Pose(later)));
  EXPECT_FALSE(engine_->TakeDueJob());
  // Scanned again: no search within the interval (poses 0.3 s apart: no loss of
  // tracking)...
  const int64_t rescan = later + 300'000'000;
  const int64_t interval_end =
      later + static_cast<int64_t>(options.recovery.search_interval_s * 1e9);
  engine_->OnMeshDelta(Wrap(Wall(1, v1::MeshDelta::UPDATED, rescan, 9.0)));
  for (int64_t t = rescan; t < interval_end - 100'000'000; t += 300'000'000) {
    engine_->OnHeadsetPose(Wrap(Pose(t)));
    EXPECT_FALSE(engine_->TakeDueJob()) << static_cast<double>(t - later) * 1e-9 << " s";
  }
  // ...and one once it is over.
  clock_ns_ = interval_end + 100'000'000;
  engine_->OnHeadsetPose(Wrap(Pose(clock_ns_)));
  auto job = engine_->TakeDueJob();
  ASSERT_TRUE(job);
  EXPECT_TRUE(job->global);
  EXPECT_GE(job->cloud.size(), options.search_min_points);
}

// An update is due, but the walls of its window are too few (the wearer's walls were
// scanned long ago): no job, and the next one is tried as soon as new walls come, not a
// whole interval later.
TEST_F(EngineInputTest, AnUpdateWithTooFewWallsInItsWindowIsTriedAgainOnTheNextWalls) {
  config_.mutable_tracking()->mutable_measurement()->set_window_s(10);
  Start(/*with_plan=*/true);
  engine_->OnCommand(Wrap(WallPickAtWall()));
  ASSERT_TRUE(engine_->tracker().has_alignment());
  const int64_t s = 1'000'000'000;
  engine_->OnMeshDelta(Wrap(Wall(1, v1::MeshDelta::ADDED, 1 * s)));
  const size_t min_points = engine_->tracker().options().min_points;
  ASSERT_GE(engine_->store().points(), min_points);
  // 20 s on, the wall is still in the store but 19 s old: out of the 10 s window.
  clock_ns_ += 19 * s;
  engine_->OnHeadsetPose(Wrap(Pose(20 * s)));
  EXPECT_FALSE(engine_->TakeDueJob());
  // Scanned again 0.3 s later, well within update_interval_s of that attempt.
  engine_->OnMeshDelta(Wrap(Wall(1, v1::MeshDelta::UPDATED, 20 * s + 300'000'000)));
  engine_->OnHeadsetPose(Wrap(Pose(20 * s + 300'000'000)));
  auto job = engine_->TakeDueJob();
  ASSERT_TRUE(job);
  EXPECT_FALSE(job->global);
  EXPECT_GE(job->cloud.size(), min_points);
}

// A building of two floors (a .floors set): the daemon follows the wearer up and down the
// stairs by the headset's height, keeps the alignment (the floors share one frame), drops
// the walls of the floor left, and is not fooled by a crouch or a short look upwards.
TEST_F(EngineInputTest, TheFloorFollowsTheHeadsetUpAndDownTheStairs) {
  Write("ground.txt", "1\n0 0 10 0\n");
  Write("first.txt", "2\n0 0 10 0\n0 5 10 5\n");
  config_.set_plan_path(
      Write("building.floors", "# id height plan\n0 0.0 ground.txt\n1 3.5 first.txt  # up\n"));
  Start(/*with_plan=*/false);
  ASSERT_TRUE(engine_->tracker().has_plan());
  engine_->OnCommand(Wrap(WallPickAtWall()));
  ASSERT_TRUE(engine_->tracker().has_alignment());
  const Se2 aligned = engine_->tracker().alignment().T_plan_slam;
  engine_->OnMeshDelta(Wrap(Wall(1, v1::MeshDelta::ADDED, 1)));
  ASSERT_GT(engine_->store().points(), 0u);

  int64_t t = 0;
  auto walk = [&](double seconds, double z_from, double z_to) {
    const int steps = static_cast<int>(seconds / 0.3);
    for (int i = 1; i <= steps; ++i) {
      t += 300'000'000;
      engine_->OnHeadsetPose(Wrap(Pose(t, 1.0, z_from + (z_to - z_from) * i / steps)));
    }
  };
  walk(3, 1.6, 1.6);
  walk(5, 0.6, 0.6);  // crouching, a metre down
  walk(1, 5.1, 5.1);  // a second at the next floor's height is not enough
  walk(3, 1.6, 1.6);
  EXPECT_EQ(c().floor_changes(), 0u);
  EXPECT_EQ(poses_.back().floor(), "0");
  EXPECT_GT(engine_->store().points(), 0u);

  const ExploredMap* ground_explored = engine_->explored();
  const ClosestWallIndex* ground_index = engine_->tracker().index().get();
  ASSERT_NE(ground_explored, nullptr);
  walk(10, 1.6, 5.1);  // up the stairs
  walk(3, 5.1, 5.1);
  EXPECT_EQ(c().floor_changes(), 1u);
  EXPECT_EQ(poses_.back().floor(), "1");
  EXPECT_NE(poses_.back().reliability().reason().find("not yet checked"), std::string::npos)
      << poses_.back().reliability().reason();
  EXPECT_EQ(engine_->store().points(), 0u);  // the ground floor's walls
  {
    // A restart upstairs resumes upstairs, though the configuration says floor 0.
    Engine restarted(
        config_, [](Topic, const google::protobuf::Message&) {}, [] { return 0; });
    restarted.Start();
    ASSERT_EQ(restarted.RestoreState(engine_->SaveState()), "");
    EXPECT_EQ(restarted.tracker().index()->plan().segments.size(), 2u);
    EXPECT_EQ(restarted.SaveState().floor(), "1");
  }
  EXPECT_EQ(engine_->tracker().index()->plan().segments.size(), 2u);
  EXPECT_TRUE(engine_->tracker().has_alignment());
  EXPECT_EQ(engine_->tracker().alignment().T_plan_slam.t, aligned.t);
  EXPECT_EQ(engine_->tracker().alignment().T_plan_slam.theta, aligned.theta);

  walk(10, 5.1, 1.7);  // and down again
  walk(3, 1.7, 1.7);
  EXPECT_EQ(c().floor_changes(), 2u);
  EXPECT_EQ(poses_.back().floor(), "0");
  EXPECT_EQ(engine_->tracker().index()->plan().segments.size(), 1u);
  // The ground floor as it was left: its explored map and index kept, not rebuilt.
  EXPECT_EQ(engine_->explored(), ground_explored);
  EXPECT_EQ(engine_->tracker().index().get(), ground_index);

  // Every floor is built at the load: a set whose upper floor's plan is gone is refused.
  std::filesystem::remove(Path("first.txt"));
  Start(/*with_plan=*/false);
  EXPECT_EQ(c().plans_refused(), 1u);
  EXPECT_FALSE(engine_->tracker().has_plan());

  // Sets that are not sets, and a floor the set lacks, are refused on load.
  for (const std::string& set :
       {std::string("0 0 ground.txt\n0 3 ground.txt\n"), std::string("0 high ground.txt\n"),
        std::string("# none\n"), std::string("0 0 ground.txt\n1 0.5 ground.txt\n"),
        std::string("7 0 ground.txt\n")}) {
    v1::Command load;
    load.set_request_id(2);
    load.mutable_load_plan()->set_path(Write("bad.floors", set));
    const uint64_t refused = c().plans_refused();
    engine_->OnCommand(Wrap(load));
    EXPECT_EQ(c().plans_refused(), refused + 1) << set;
  }
}

TEST_F(EngineInputTest, AFloodOfBadInputLogsOnceASecond) {
  Start(/*with_plan=*/true);
  std::ostringstream log;
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>(
      "capture", std::make_shared<spdlog::sinks::ostream_sink_st>(log)));
  for (int i = 0; i < 1000; ++i) engine_->OnMeshDelta(Raw("garbage"));
  clock_ns_ += 2'000'000'000;
  engine_->OnMeshDelta(Raw("garbage"));
  spdlog::set_default_logger(previous);
  EXPECT_EQ(c().malformed(), 1001u);
  const std::string text = log.str();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 2) << text;
  EXPECT_NE(
      text.find("rejected: malformed MeshDelta protobuf (999 more like it in the last second)"),
      std::string::npos)
      << text;
}

}  // namespace
}  // namespace floorpose::platform
