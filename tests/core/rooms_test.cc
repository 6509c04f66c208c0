#include "core/rooms.h"

#include <gtest/gtest.h>

#include <set>

#include "core/explored_map.h"
#include "tests/sim_test_plans.h"

namespace floorpose {
namespace {

using testing::SyntheticOffice;

TEST(RoomMapTest, EveryOfficeIsARoomAndTheCorridorIsOne) {
  const FloorPlan plan = SyntheticOffice(4);
  const RoomMap rooms(plan);
  EXPECT_EQ(rooms.doors().size(), 8u);  // one per office
  ASSERT_EQ(rooms.rooms().size(), 9u);  // 8 offices and the corridor
  std::set<int> ids;
  for (int i = 0; i < 4; ++i) {
    ids.insert(rooms.RoomAt({5.0 * i + 2.5, 4.0}));
    ids.insert(rooms.RoomAt({5.0 * i + 2.5, -2.0}));
  }
  const int corridor = rooms.RoomAt({1.0, 1.0});
  EXPECT_EQ(rooms.RoomAt({19.0, 1.0}), corridor);
  ids.insert(corridor);
  EXPECT_EQ(ids.size(), 9u);
  EXPECT_EQ(ids.count(-1), 0u);
  EXPECT_EQ(rooms.RoomAt({-5, -5}), -1);    // outside
  EXPECT_EQ(rooms.RoomAt({2.5, 2.0}), -1);  // in a doorway
  for (const Room& room : rooms.rooms()) {
    EXPECT_EQ(rooms.RoomAt(room.centre), room.id);
    EXPECT_GT(room.area_m2, 10.0);
  }
  // 5 x 4 m, less the cells walls pass through.
  EXPECT_GT(rooms.rooms()[rooms.RoomAt({2.5, 4.0})].area_m2, 17.5);
  EXPECT_LE(rooms.rooms()[rooms.RoomAt({2.5, 4.0})].area_m2, 20.0);
}

TEST(RoomMapTest, AWideOpeningJoinsWhatItConnects) {
  // The hall is open to the corridor over 2 m: one room with it.
  const RoomMap rooms(SyntheticOffice(2, 12.0));
  EXPECT_EQ(rooms.rooms().size(), 5u);
  EXPECT_EQ(rooms.RoomAt({1.0, 1.0}), rooms.RoomAt({16.0, 1.0}));
}

TEST(ExploredMapTest, RaysClearTheRoomAndMarkItsWalls) {
  const FloorPlan plan = SyntheticOffice(2);
  auto rooms = std::make_shared<RoomMap>(plan);
  ExploredMap map(plan, rooms);
  std::vector<Eigen::Vector2d> walls;
  for (double x = 0.2; x < 5; x += 0.1) walls.push_back({x, 5.98});  // the room's north wall
  map.AddWalls({2.5, 4.0}, walls);
  EXPECT_LT(map.LogOdds({2.5, 5.0}), 0.0f);
  EXPECT_GT(map.LogOdds({2.5, 5.98}), 0.0f);
  EXPECT_EQ(map.LogOdds({2.5, -2.0}), 0.0f);  // not seen
  // Far points are not rays.
  const uint64_t before = map.revision();
  map.AddWalls({2.5, 4.0}, {{2.5, 40.0}});
  EXPECT_EQ(map.revision(), before);

  EXPECT_TRUE(map.VisitedRooms().empty());
  for (int i = 0; i < 3; ++i) map.AddVisit({2.5, 4.0});
  map.AddVisit({7.5, -2.0});
  EXPECT_EQ(map.VisitedRooms(), std::vector<int>{rooms->RoomAt({2.5, 4.0})});
  EXPECT_LT(map.LogOdds({7.5, -2.0}), 0.0f);

  // A second wearer's map adds up.
  ExploredMap other(plan, rooms);
  for (int i = 0; i < 2; ++i) other.AddVisit({7.5, -2.0});
  ASSERT_TRUE(map.Merge(other));
  EXPECT_EQ(map.VisitedRooms().size(), 2u);
  ExploredOptions coarse;
  coarse.cell_m = 0.2;
  EXPECT_FALSE(map.Merge(ExploredMap(plan, rooms, coarse)));
  // Log-odds stay clamped.
  for (int i = 0; i < 100; ++i) map.AddWalls({2.5, 4.0}, walls);
  EXPECT_LE(map.LogOdds({2.5, 5.98}), 3.5f);
  EXPECT_GE(map.LogOdds({2.5, 5.0}), -3.5f);
}

}  // namespace
}  // namespace floorpose
