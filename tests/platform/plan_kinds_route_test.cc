// Routes on a plan as buildings are drawn: two rooms, a door drawn over the wall between
// them, a window and an exit in the outer walls. A route passes the door and never a
// window; the way out goes to the exit, not to the nearer window.
#include <gtest/gtest.h>

#include <string>

#include "core/route_planner.h"
#include "platform/floor_plan_io.h"
#include "tests/route_test_util.h"

namespace floorpose::platform {
namespace {

std::string Line(double x0, double y0, double x1, double y1, const std::string& kind) {
  return R"({"type":"Feature","properties":{"kind":")" + kind +
         R"("},"geometry":{"type":"LineString","coordinates":[[)" + std::to_string(x0) + "," +
         std::to_string(y0) + "],[" + std::to_string(x1) + "," + std::to_string(y1) + "]]}}";
}

// 0..12 x 0..6: the wall x = 6 between the rooms is drawn whole with a door on it at
// y 1..2.2; the east wall has a window at y 2..5 (in the wall line's gap); the west wall
// an exit at y 4..5.2.
FloorPlan TwoRooms() {
  const std::string features[] = {Line(0, 0, 12, 0, "wall"),  Line(0, 6, 12, 6, "wall"),
                                  Line(6, 0, 6, 6, "wall"),   Line(6, 1, 6, 2.2, "door"),
                                  Line(12, 0, 12, 2, "wall"), Line(12, 2, 12, 5, "window"),
                                  Line(12, 5, 12, 6, "wall"), Line(0, 0, 0, 4, "wall"),
                                  Line(0, 4, 0, 5.2, "exit"), Line(0, 5.2, 0, 6, "wall")};
  std::string doc = R"({"type":"FeatureCollection","properties":{"units":"m"},"features":[)";
  for (const std::string& f : features) doc += f + (&f == &features[9] ? "" : ",");
  const FloorPlanParse parse = ParseGeoJsonFloorPlan(doc + "]}", "two-rooms");
  EXPECT_TRUE(parse.ok()) << parse.error;
  return parse.plan;
}

// Whether a leg of the path crosses the segment.
bool Crosses(const std::vector<Eigen::Vector2d>& path, const Segment& s) {
  for (size_t i = 1; i < path.size(); ++i)
    if (testing::SegmentDistance({path[i - 1], path[i]}, s) == 0.0) return true;
  return false;
}

TEST(PlanKindsRouteTest, PassesTheDoorNeverTheWindow) {
  const FloorPlan plan = TwoRooms();
  ASSERT_EQ(plan.openings.size(), 2u);
  const RoutePlanner planner(plan);
  const Segment door{{6, 1}, {6, 2.2}}, window{{12, 2}, {12, 5}};
  const Route across = planner.Plan({2, 3}, {10, 3});
  ASSERT_TRUE(across.ok()) << across.error;
  EXPECT_TRUE(Crosses(across.path, door));
  EXPECT_GT(testing::PathClearance(across.path, plan.segments), 0.29);

  // Out of the east room: the window is 2 m away, the exit beyond the door.
  const Route out = planner.WayOut({10, 3.5});
  ASSERT_TRUE(out.ok()) << out.error;
  EXPECT_FALSE(Crosses(out.path, window));
  EXPECT_TRUE(Crosses(out.path, door));
  EXPECT_LT((out.path.back() - Eigen::Vector2d(0, 4.6)).norm(), 1.0);
  EXPECT_GT(out.length_m, 10.0);

  // A plan without exits has no way out; one with stairs goes down them.
  FloorPlan closed = plan;
  closed.openings.pop_back();
  EXPECT_FALSE(RoutePlanner(closed).WayOut({10, 3.5}).ok());
}

}  // namespace
}  // namespace floorpose::platform
