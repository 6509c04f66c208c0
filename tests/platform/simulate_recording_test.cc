// `floorpose simulate` recordings: byte-identical per seed, different for another seed;
// laid out as the daemon receives its inputs (SimulationInfo first, then per pose its mesh
// deltas, the pose and its ground truth, the wall pick after the first poses), with
// virtual stamps and per-topic sequence numbers; TUM trajectories parsed as documented.
#include "tools/lib/simulate_recording.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <map>
#include <set>

#include "core/frames.h"
#include "platform/recording.h"
#include "tests/sim_test_plans.h"
#include "tests/test_util.h"

namespace floorpose::tools {
namespace {

using ::testing::HasSubstr;

class SimulateRecordingTest : public testing::TempDirTest {
 protected:
  static sim::SimulatorOptions Options(uint64_t seed) {
    sim::SimulatorOptions o;
    o.seed = seed;
    o.scenario = sim::Scenario::kOffice;
    o.target_length_m = 40.0;
    return o;
  }

  std::string Simulate(const std::string& name, const sim::SimulatorOptions& o,
                       SimulateRecordingResult* result = nullptr,
                       const std::vector<sim::TimedPose>* trajectory = nullptr) {
    SimulateRecordingResult local;
    std::string error;
    const std::string path = Path(name);
    EXPECT_TRUE(SimulateToRecording(testing::SyntheticOffice(), o, trajectory, {}, path,
                                    result ? result : &local, &error))
        << error;
    return path;
  }

  static std::vector<v1::RecordingRecord> ReadAll(const std::string& path) {
    platform::RecordingReader reader(path);
    EXPECT_TRUE(reader.ok()) << reader.error();
    std::vector<v1::RecordingRecord> out;
    v1::RecordingRecord r;
    while (reader.Next(&r)) out.push_back(r);
    EXPECT_TRUE(reader.error().empty()) << reader.error();
    return out;
  }
};

TEST_F(SimulateRecordingTest, SameSeedGivesTheSameBytes) {
  const std::string a = testing::ReadText(Simulate("a.rec", Options(11)));
  const std::string b = testing::ReadText(Simulate("b.rec", Options(11)));
  const std::string c = testing::ReadText(Simulate("c.rec", Options(12)));
  ASSERT_GT(a.size(), 10000u);
  EXPECT_TRUE(a == b) << "two runs with seed 11 differ";
  EXPECT_FALSE(a == c) << "seeds 11 and 12 gave the same recording";
}

TEST_F(SimulateRecordingTest, LaidOutAsTheDaemonReceivesIt) {
  SimulateRecordingResult result;
  const std::string path = Simulate("walk.rec", Options(3), &result);
  const sim::Simulation& sim = result.simulation;
  const std::vector<v1::RecordingRecord> records = ReadAll(path);
  ASSERT_EQ(records.size(), result.records);
  EXPECT_EQ(result.bytes, testing::ReadText(path).size());

  ASSERT_FALSE(records.empty());
  ASSERT_EQ(records[0].topic(), kSimInfoTopic);
  v1::SimulationInfo info;
  ASSERT_TRUE(info.ParseFromString(records[0].envelope().payload()));
  EXPECT_EQ(info.plan_id(), "synthetic-office");
  EXPECT_EQ(info.scenario(), "office");
  EXPECT_EQ(info.seed(), 3u);
  EXPECT_EQ(info.device_id(), "sim-headset");
  EXPECT_DOUBLE_EQ(info.length_m(), sim.length_m);
  EXPECT_DOUBLE_EQ(info.duration_s(), sim.duration_s);
  EXPECT_DOUBLE_EQ(info.t_slam_plan_initial().theta(), sim.T_slam_plan_initial.theta);
  EXPECT_THAT(info.description(), HasSubstr("desks"));

  const std::string mesh_topic = platform::TopicName(platform::Topic::kMeshDelta);
  const std::string pose_topic = platform::TopicName(platform::Topic::kHeadsetPose);
  const std::string command_topic = platform::TopicName(platform::Topic::kCommand);
  std::map<std::string, uint64_t> seq;
  int64_t last_stamp = 0;
  size_t poses = 0, meshes = 0, commands = 0, truths = 0;
  std::set<uint32_t> markers;
  for (size_t i = 0; i < records.size(); ++i) {
    const v1::RecordingRecord& r = records[i];
    const v1::Envelope& e = r.envelope();
    EXPECT_EQ(e.device_id(), "sim-headset");
    EXPECT_EQ(e.seq(), ++seq[r.topic()]) << r.topic();
    EXPECT_EQ(e.stamp_ns(), r.receive_stamp_ns());
    EXPECT_GE(r.receive_stamp_ns(), last_stamp);
    last_stamp = r.receive_stamp_ns();
    if (r.topic() == pose_topic) {
      ASSERT_LT(poses, sim.steps.size());
      const sim::SimulatedStep& step = sim.steps[poses++];
      v1::HeadsetPose pose;
      ASSERT_TRUE(pose.ParseFromString(e.payload()));
      EXPECT_EQ(pose.stamp_ns(), step.stamp_ns);
      // Back through the daemon's ingest conversion: the simulated slam pose.
      const Pose2 slam =
          HeadsetPoseToSlam(HeadsetFrame::kUnityLeftHandedYUp,
                            {pose.position().x(), pose.position().y(), pose.position().z()},
                            Eigen::Quaterniond(pose.orientation().w(), pose.orientation().x(),
                                               pose.orientation().y(), pose.orientation().z()));
      EXPECT_NEAR((slam.position - step.slam.position).norm(), 0.0, 1e-9);
      EXPECT_NEAR(WrapAngle(slam.heading - step.slam.heading), 0.0, 1e-9);
      // Its ground truth follows at once.
      ASSERT_LT(i + 1, records.size());
      ASSERT_EQ(records[i + 1].topic(), kGroundTruthTopic);
      v1::GroundTruthPose truth;
      ASSERT_TRUE(truth.ParseFromString(records[i + 1].envelope().payload()));
      EXPECT_EQ(truth.stamp_ns(), step.stamp_ns);
      EXPECT_DOUBLE_EQ(truth.x(), step.true_plan.position.x());
      EXPECT_DOUBLE_EQ(truth.heading(), step.true_plan.heading);
      EXPECT_EQ(truth.floor(), "0");
      if (truth.marker()) {
        EXPECT_TRUE(markers.insert(truth.marker()).second);
      }
    } else if (r.topic() == kSimInfoTopic) {
      EXPECT_EQ(i, 0u);
    } else if (r.topic() == kGroundTruthTopic) {
      ++truths;
    } else if (r.topic() == mesh_topic) {
      v1::MeshDelta mesh;
      ASSERT_TRUE(mesh.ParseFromString(e.payload()));
      EXPECT_NE(mesh.change(), v1::MeshDelta::CHANGE_UNSPECIFIED);
      EXPECT_EQ(mesh.vertices_size() % 3, 0);
      EXPECT_EQ(mesh.stamp_ns(), e.stamp_ns());
      ++meshes;
    } else if (r.topic() == command_topic) {
      ++commands;
      EXPECT_GT(poses, 0u);
      EXPECT_GT(meshes, 0u);  // right after the first poses and meshes
      v1::Command command;
      ASSERT_TRUE(command.ParseFromString(e.payload()));
      ASSERT_TRUE(command.has_wall_pick());
      const auto& p = command.wall_pick();
      const Eigen::Vector3d point =
          PointToSlam(HeadsetFrame::kUnityLeftHandedYUp,
                      {p.headset_point().x(), p.headset_point().y(), p.headset_point().z()});
      EXPECT_NEAR((point.head<2>() - sim.pick.slam_point).norm(), 0.0, 1e-9);
      EXPECT_NEAR(p.plan_x(), sim.pick.plan_point.x(), 1e-12);
    } else {
      ADD_FAILURE() << "unexpected topic " << r.topic();
    }
  }
  EXPECT_EQ(poses, sim.steps.size());
  EXPECT_EQ(truths, sim.steps.size());
  EXPECT_EQ(commands, 1u);
  EXPECT_EQ(meshes, sim.counts.added + sim.counts.updated + sim.counts.removed);
  EXPECT_EQ(markers.size(), 10u);
}

TEST_F(SimulateRecordingTest, FollowsATumTrajectory) {
  const std::string text =
      "# timestamp x y z qx qy qz qw\n"
      "10.0 1.0 1.0 1.6 0 0 0 1\n"
      "\n"
      "14.0 6.0 1.0 1.6 0 0 0 1  # along the corridor\n"
      "20.0 14.0 1.0 1.6 0 0 0.7071067811865476 0.7071067811865476\n";
  std::vector<sim::TimedPose> trajectory;
  std::string error;
  ASSERT_TRUE(ParseTumTrajectory(text, &trajectory, &error)) << error;
  ASSERT_EQ(trajectory.size(), 3u);
  EXPECT_DOUBLE_EQ(trajectory[1].t_s, 14.0);
  EXPECT_EQ(trajectory[1].position, Eigen::Vector2d(6.0, 1.0));
  EXPECT_NEAR(trajectory[0].heading, 0.0, 1e-12);
  EXPECT_NEAR(trajectory[2].heading, M_PI / 2, 1e-12);  // 90 degrees about z: x turns to y

  SimulateRecordingResult result;
  Simulate("tum.rec", Options(1), &result, &trajectory);
  ASSERT_EQ(result.simulation.steps.size(), 34u);  // 0 to 9.9 s every 0.3 s
  EXPECT_NEAR(result.simulation.length_m, 5.0 + 8.0 * 5.9 / 6.0, 1e-9);
}

TEST(TumTrajectoryTest, RefusesBrokenInput) {
  std::vector<sim::TimedPose> out;
  std::string error;
  EXPECT_FALSE(ParseTumTrajectory("1 0 0 0 0 0 0 1\n2 1 0 0 0 0 1\n", &out, &error));
  EXPECT_THAT(error, HasSubstr("line 2"));
  out.clear();
  EXPECT_FALSE(ParseTumTrajectory("1 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n", &out, &error));
  EXPECT_THAT(error, HasSubstr("increase"));
  out.clear();
  EXPECT_FALSE(ParseTumTrajectory("1 0 0 0 0 0 0 0\n2 1 0 0 0 0 0 1\n", &out, &error));
  out.clear();
  EXPECT_FALSE(ParseTumTrajectory("1 0 0 0 0 0 0 1\n", &out, &error));
  EXPECT_THAT(error, HasSubstr("two poses"));
}

TEST(WaypointsTest, ReadsWalksInFileOrderAndDropsRepeatedTimes) {
  WaypointWalks walks;
  std::string error;
  ASSERT_TRUE(
      ParseWaypoints("walk,t_ms,x_m,y_m\r\nb,1000,1.5,2\r\na,500,0,0\r\nb,2000,3,2\r\n"
                     "b,2000,9,9\r\na,1500,0,4\r\n",
                     &walks, &error))
      << error;
  ASSERT_EQ(walks.ids, (std::vector<std::string>{"b", "a"}));
  ASSERT_EQ(walks.walks["b"].size(), 2u);  // the second waypoint at 2000 ms went
  EXPECT_EQ(walks.repeated, 1u);
  EXPECT_DOUBLE_EQ(walks.walks["b"][0].t_s, 1.0);
  EXPECT_EQ(walks.walks["b"][1].position, Eigen::Vector2d(3, 2));
  EXPECT_EQ(walks.walks["a"][1].position, Eigen::Vector2d(0, 4));
}

TEST(WaypointsTest, RefusesBrokenInputNamingTheLine) {
  const char* broken[] = {
      "walk,t_ms,x_m,y_m\na,1,2\n",              // too few fields
      "walk,t_ms,x_m,y_m\na,1,2,3,4\n",          // too many
      "walk,t_ms,x_m,y_m\na,1,2,north\n",        // not a number
      "walk,t_ms,x_m,y_m\na,1,nan,3\n",          // not finite
      "walk,t_ms,x_m,y_m\n,1,2,3\n",             // no walk id
      "walk,t_ms,x_m,y_m\na,10,0,0\na,5,1,1\n",  // back in time
  };
  for (const char* text : broken) {
    WaypointWalks walks;
    std::string error;
    EXPECT_FALSE(ParseWaypoints(text, &walks, &error)) << text;
    EXPECT_THAT(error, HasSubstr("line ")) << text;
  }
  WaypointWalks none;
  std::string error;
  EXPECT_FALSE(ParseWaypoints("walk,t_ms,x_m,y_m\n", &none, &error));
  EXPECT_THAT(error, HasSubstr("no waypoints"));
}

}  // namespace
}  // namespace floorpose::tools
