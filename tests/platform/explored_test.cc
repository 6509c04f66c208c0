// The explored map of a simulated walk through the daemon's code (Evaluate): its free
// cells are where the wearer walked and looked, and its room list is the rooms the
// ground truth entered.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "core/explored_map.h"
#include "core/rooms.h"
#include "platform/explored_codec.h"
#include "tests/sim_test_plans.h"
#include "tests/test_util.h"
#include "tools/lib/evaluation.h"
#include "tools/lib/simulate_recording.h"

namespace floorpose::tools {
namespace {

class ExploredTest : public testing::TempDirTest {};

TEST_F(ExploredTest, TheExploredGridMatchesTheWalkedRooms) {
  const FloorPlan plan = testing::SyntheticOffice(6);
  sim::SimulatorOptions o;
  o.seed = 4;
  o.scenario = sim::Scenario::kOffice;
  o.target_length_m = 150.0;
  SimulateRecordingResult simulated;
  std::string error;
  const std::string recording = Path("walk.rec");
  ASSERT_TRUE(SimulateToRecording(plan, o, nullptr, {}, recording, &simulated, &error)) << error;
  v1::FloorposedConfig config;
  config.set_plan_path(Write("office.txt", testing::ThesisText(plan)));
  EvalReport report;
  ASSERT_TRUE(Evaluate(config, recording, Baseline::kNone, &report, &error)) << error;
  ASSERT_TRUE(report.explored.has_value());
  const v1::ExploredMap& msg = *report.explored;

  // The receiver's side: the same plan, the same rooms, the message's cells.
  auto rooms = std::make_shared<const RoomMap>(plan);
  ExploredMap map(plan, rooms);
  ASSERT_EQ(platform::FromProto(msg, &map), "");
  EXPECT_EQ(msg.rooms(), rooms->rooms().size());
  EXPECT_EQ(msg.rooms(), 13u);  // 12 offices and the corridor

  // The truth: where the wearer was at every RELIABLE pose.
  std::map<int64_t, bool> reliable;
  for (const v1::PlanPose& p : report.plan_poses)
    reliable[p.source_stamp_ns()] = p.reliability().flag() == v1::Reliability::RELIABLE;
  std::map<int, int> truth_poses;
  size_t walked = 0, walked_free = 0;
  for (const sim::SimulatedStep& step : simulated.simulation.steps) {
    if (!reliable[step.stamp_ns]) continue;
    ++walked;
    walked_free += map.LogOdds(step.true_plan.position) < 0;
    const int room = rooms->RoomAt(step.true_plan.position);
    if (room >= 0) ++truth_poses[room];
  }
  ASSERT_GT(walked, 200u);
  // Where the wearer walked is free (the estimate is decimetres off, the footprint 0.3 m).
  EXPECT_GE(static_cast<double>(walked_free), 0.98 * static_cast<double>(walked));

  // Visited rooms: every room the truth spent a few seconds in, and none it never entered.
  std::set<int> visited;
  for (const auto& r : msg.visited()) visited.insert(static_cast<int>(r.id()));
  std::set<int> entered, stayed;
  for (const auto& [room, poses] : truth_poses) {
    entered.insert(room);
    if (poses >= 10) stayed.insert(room);
  }
  ASSERT_GE(stayed.size(), 3u) << "the walk should enter a few offices";
  ASSERT_LT(entered.size(), rooms->rooms().size()) << "the walk should leave some rooms out";
  for (int room : stayed) EXPECT_TRUE(visited.count(room)) << "room " << room << " missing";
  for (int room : visited) EXPECT_TRUE(entered.count(room)) << "room " << room << " never entered";

  // Seen free: a good part of every stayed-in room (meshes come once per surface, so a
  // room scanned before the position was RELIABLE is seen less), little of the rooms never
  // entered (only what shows through their doors); and nothing far from the walk.
  std::map<int, size_t> cells, seen;
  const GridGeometry& g = map.grid();
  for (int i = 0; i < static_cast<int>(g.size()); ++i) {
    const int room = rooms->RoomAt(g.CellCentre(i));
    if (room < 0) continue;
    ++cells[room];
    seen[room] += map.log_odds()[i] < 0;
  }
  for (const auto& [room, n] : cells) {
    const double share = static_cast<double>(seen[room]) / static_cast<double>(n);
    std::printf("room %d: %s, %.0f%% seen free\n", room,
                stayed.count(room)    ? "stayed"
                : entered.count(room) ? "entered"
                                      : "never entered",
                100 * share);
    if (stayed.count(room)) {
      EXPECT_GE(share, 0.15) << "room " << room;
    }
    if (!entered.count(room)) {
      EXPECT_LE(share, 0.2) << "room " << room;
    }
  }
  std::vector<Eigen::Vector2d> path;
  for (const sim::SimulatedStep& step : simulated.simulation.steps)
    if (reliable[step.stamp_ns]) path.push_back(step.true_plan.position);
  size_t free = 0, far = 0;
  for (int i = 0; i < static_cast<int>(g.size()); ++i) {
    if (map.log_odds()[i] >= 0) continue;
    ++free;
    double nearest = 1e9;
    for (const Eigen::Vector2d& p : path) nearest = std::min(nearest, (p - g.CellCentre(i)).norm());
    far += nearest > 6.5;  // ExploredOptions::max_ray_m, and the estimate's error
  }
  EXPECT_EQ(far, 0u) << "of " << free << " free cells";
  EXPECT_GT(msg.wall_cells(), 0u);
  EXPECT_GT(msg.free_cells(), 0u);
}

}  // namespace
}  // namespace floorpose::tools
