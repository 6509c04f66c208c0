// The team's markers and roster as a daemon and a dashboard keep them (platform/team.h).
#include "platform/team.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

namespace floorpose::platform {
namespace {

v1::Marker Blocked(const std::string& id, double x, double y, uint64_t revision = 1) {
  v1::Marker m;
  m.set_id(id);
  m.set_kind(v1::Marker::BLOCKED);
  m.set_plan_id("office");
  m.set_floor("0");
  m.set_x(x);
  m.set_y(y);
  m.set_revision(revision);
  m.set_created_unix_ns(static_cast<int64_t>(revision) * 1000);
  return m;
}

TEST(MarkerBoardTest, TheHighestRevisionWinsAndARemovalStays) {
  MarkerBoard board;
  std::string why;
  EXPECT_EQ(board.Merge(Blocked("lead-1", 3, 4), &why), MarkerBoard::Take::kNew);
  EXPECT_EQ(board.Merge(Blocked("lead-1", 3, 4), &why), MarkerBoard::Take::kKnown);
  EXPECT_EQ(board.KeepOuts("office", "0").size(), 1u);
  EXPECT_EQ(board.KeepOuts("office", "1").size(), 0u) << "another floor";
  EXPECT_EQ(board.KeepOuts("lab", "0").size(), 0u) << "another plan";
  EXPECT_DOUBLE_EQ(board.KeepOuts("office", "0")[0].radius_m, MarkerBoard::kDefaultRadiusM);
  v1::Marker removed = Blocked("lead-1", 3, 4, 2);
  removed.set_removed(true);
  EXPECT_EQ(board.Merge(removed, &why), MarkerBoard::Take::kReplaced);
  EXPECT_EQ(board.KeepOuts("office", "0").size(), 0u);
  // An old copy heard late (a restarted holder) does not bring it back.
  EXPECT_EQ(board.Merge(Blocked("lead-1", 3, 4, 1), &why), MarkerBoard::Take::kKnown);
  EXPECT_TRUE(board.markers().at("lead-1").removed());
  v1::Marker note = Blocked("hl-07-1", 1, 1);
  note.set_kind(v1::Marker::NOTE);
  EXPECT_EQ(board.Merge(note, &why), MarkerBoard::Take::kNew);
  EXPECT_EQ(board.KeepOuts("office", "0").size(), 0u) << "a note keeps no one out";
}

TEST(MarkerBoardTest, RefusesWhatIsNotAMarkerAndStaysBounded) {
  MarkerBoard board;
  std::string why;
  EXPECT_EQ(board.Merge(Blocked("", 0, 0), &why), MarkerBoard::Take::kRefused);
  EXPECT_EQ(board.Merge(Blocked("a b", 0, 0), &why), MarkerBoard::Take::kRefused);
  EXPECT_NE(why.find("not one"), std::string::npos) << why;
  EXPECT_EQ(board.Merge(Blocked("nan", NAN, 0), &why), MarkerBoard::Take::kRefused);
  EXPECT_EQ(board.Merge(Blocked("far", 1e300, 0), &why), MarkerBoard::Take::kRefused);
  v1::Marker wide = Blocked("wide", 0, 0);
  wide.set_radius_m(-1);
  EXPECT_EQ(board.Merge(wide, &why), MarkerBoard::Take::kRefused);
  for (size_t i = 0; i < MarkerBoard::kCapacity; ++i) {
    v1::Marker m = Blocked("m" + std::to_string(i), 1, 1);
    m.set_removed(i < 10);
    ASSERT_EQ(board.Merge(m, &why), MarkerBoard::Take::kNew) << why;
  }
  // Full: a removed one makes room, ten times; then the board refuses.
  for (int i = 0; i < 10; ++i)
    EXPECT_EQ(board.Merge(Blocked("x" + std::to_string(i), 2, 2), &why), MarkerBoard::Take::kNew);
  EXPECT_EQ(board.Merge(Blocked("y", 2, 2), &why), MarkerBoard::Take::kRefused);
  EXPECT_NE(why.find("full"), std::string::npos) << why;
  EXPECT_EQ(board.markers().size(), MarkerBoard::kCapacity);
}

TEST(MarkerBoardTest, SurvivesARestartThroughItsFile) {
  const std::string path = (std::filesystem::path(::testing::TempDir()) /
                            ("markers-" + std::to_string(getpid()) + ".pb"))
                               .string();
  MarkerBoard board;
  std::string why, error;
  board.Merge(Blocked("lead-1", 3, 4), &why);
  board.Merge(Blocked("lead-2", 5, 4), &why);
  ASSERT_TRUE(board.Save(path, &error)) << error;
  MarkerBoard again;
  ASSERT_TRUE(again.Load(path, &error)) << error;
  EXPECT_EQ(again.markers().size(), 2u);
  EXPECT_EQ(again.markers().at("lead-2").x(), 5.0);
  MarkerBoard none;
  EXPECT_TRUE(none.Load(path + ".missing", &error)) << "a first start";
  std::filesystem::remove(path);
}

TEST(MarkerKindTest, NamesAsPeopleWriteThem) {
  v1::Marker::Kind kind{};
  for (const char* name : {"hazard", "victim", "searched", "blocked", "note"}) {
    ASSERT_TRUE(ParseMarkerKind(name, &kind)) << name;
    EXPECT_EQ(MarkerKindName(kind), name);
  }
  EXPECT_TRUE(ParseMarkerKind("HAZARD", &kind));
  EXPECT_FALSE(ParseMarkerKind("kind_unspecified", &kind));
  EXPECT_FALSE(ParseMarkerKind("dragon", &kind));
  EXPECT_FALSE(ParseMarkerKind("", &kind));
}

TEST(RosterTest, KeepsEveryWearersLatestPoseAndState) {
  Roster roster;
  auto pose = [](double x, int64_t stamp) {
    v1::PlanPose p;
    p.set_x(x);
    p.set_y(1);
    p.set_source_stamp_ns(stamp);
    p.set_floor("0");
    return p.SerializeAsString();
  };
  v1::DaemonStatus status;
  status.set_state(v1::DaemonStatus::TRACKING);
  status.set_plan_id("office");
  status.mutable_alert()->set_kind(v1::Alert::NO_MOTION);
  EXPECT_TRUE(roster.Take(Topic::kPlanPose, {"hl-a", 1, 0, pose(1, 100)}, 1'000'000'000));
  EXPECT_TRUE(roster.Take(Topic::kPlanPose, {"hl-b", 1, 0, pose(2, 100)}, 1'000'000'000));
  EXPECT_TRUE(
      roster.Take(Topic::kStatus, {"hl-b", 2, 0, status.SerializeAsString()}, 1'000'000'000));
  EXPECT_FALSE(roster.Take(Topic::kPlanPose, {"hl-a", 3, 0, pose(9, 50)}, 2'000'000'000))
      << "a late pose moves no one";
  EXPECT_FALSE(roster.Take(Topic::kPlanPose, {"hl-c", 1, 0, "\xff\xff"}, 0)) << "not a PlanPose";
  EXPECT_FALSE(roster.Take(Topic::kAlignment, {"hl-d", 1, 0, ""}, 0));
  const std::vector<v1::Teammate> team = roster.Teammates(3'000'000'000);
  ASSERT_EQ(team.size(), 2u);
  EXPECT_EQ(team[0].device_id(), "hl-a");
  EXPECT_EQ(team[0].pose().x(), 1.0);
  EXPECT_DOUBLE_EQ(team[0].pose_age_s(), 2.0);
  EXPECT_EQ(team[1].state(), v1::DaemonStatus::TRACKING);
  EXPECT_EQ(team[1].plan_id(), "office");
  EXPECT_EQ(team[1].alert().kind(), v1::Alert::NO_MOTION);
}

}  // namespace
}  // namespace floorpose::platform
