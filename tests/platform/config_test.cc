// floorposed configuration: protobuf text format, every option declared once in
// proto/floorpose/v1/config.proto with its default, and printed resolved.
#include "platform/config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <google/protobuf/descriptor.h>

#include "tests/test_util.h"

namespace floorpose::platform {
namespace {

using ::testing::HasSubstr;
using ::testing::IsEmpty;
namespace pb = google::protobuf;

TEST(ConfigTest, EmptyTextGivesDefaults) {
  v1::FloorposedConfig c;
  std::string error;
  ASSERT_TRUE(ParseConfig("", &c, &error)) << error;
  EXPECT_EQ(c.headset_frame(), "unity");
  EXPECT_EQ(c.walls().density_per_m2(), 50.0);
  EXPECT_EQ(c.icp().max_iterations(), 50u);
  EXPECT_EQ(c.tracking().max_points(), 20000u);
  EXPECT_EQ(c.dds().device_id(), "hololens-1");
  EXPECT_EQ(c.log_level(), "info");
  EXPECT_THAT(ValidateConfig(c), IsEmpty());
}

TEST(ConfigTest, ProtoDefaultsMatchTheCoreDefaults) {
  // The core's option structs and the config schema each carry defaults; they must
  // agree, or the daemon and the offline tools would run different algorithms.
  const v1::FloorposedConfig c;
  const TrackerOptions t = ToTrackerOptions(c);
  const TrackerOptions core;
  EXPECT_EQ(t.icp.max_iterations, core.icp.max_iterations);
  EXPECT_EQ(t.icp.levels, core.icp.levels);
  EXPECT_EQ(t.icp.reject_sigma, core.icp.reject_sigma);
  EXPECT_EQ(t.icp.max_correspondence_m, core.icp.max_correspondence_m);
  EXPECT_EQ(t.icp.converge_translation_m, core.icp.converge_translation_m);
  EXPECT_EQ(t.icp.converge_rotation_rad, core.icp.converge_rotation_rad);
  EXPECT_EQ(t.icp.cauchy_scale_factor, core.icp.cauchy_scale_factor);
  EXPECT_EQ(t.icp.inlier_threshold_m, core.icp.inlier_threshold_m);
  EXPECT_EQ(t.icp.degeneracy_ratio, core.icp.degeneracy_ratio);
  EXPECT_EQ(t.method, core.method);
  EXPECT_EQ(t.wall_buffer_m, core.wall_buffer_m);
  EXPECT_EQ(t.local_meshes, core.local_meshes);
  // The config gives the Hough settings in degrees; 1e-12 rad is far below a bin.
  EXPECT_NEAR(t.hough.max_rotation_rad, core.hough.max_rotation_rad, 1e-12);
  EXPECT_NEAR(t.hough.bin_rad, core.hough.bin_rad, 1e-12);
  EXPECT_EQ(t.hough.smooth_rad, core.hough.smooth_rad);
  EXPECT_EQ(t.min_new_points, core.min_new_points);
  EXPECT_EQ(t.max_interval_s, core.max_interval_s);
  EXPECT_EQ(t.min_points, core.min_points);
  EXPECT_EQ(t.pick_sigma_m, core.pick_sigma_m);
  EXPECT_NEAR(t.pick_sigma_rad, core.pick_sigma_rad, 1e-4);
  EXPECT_NEAR(t.filter.heading_var_per_m, core.filter.heading_var_per_m, 1e-8);
  EXPECT_NEAR(t.filter.position_var_per_m, core.filter.position_var_per_m, 1e-12);
  EXPECT_EQ(t.filter.yaw_scale_sigma, core.filter.yaw_scale_sigma);
  EXPECT_EQ(t.filter.measurement_points, core.filter.measurement_points);
  EXPECT_EQ(t.reliability.weights, core.reliability.weights);
  EXPECT_EQ(t.min_walk_m, core.min_walk_m);
  EXPECT_EQ(t.max_ambiguity, core.max_ambiguity);
  EXPECT_EQ(t.first_inlier_ratio, core.first_inlier_ratio);
  EXPECT_EQ(t.searched_first_inlier_ratio, core.searched_first_inlier_ratio);
  EXPECT_EQ(t.jump_clear_ratio, core.jump_clear_ratio);
  EXPECT_EQ(t.jump_clear_inliers, core.jump_clear_inliers);
  EXPECT_EQ(t.search_unexplained, core.search_unexplained);
  EXPECT_EQ(t.clear_ambiguity, core.clear_ambiguity);
  EXPECT_EQ(t.pick_tie_ratio, core.pick_tie_ratio);
  EXPECT_EQ(t.search_sigmas, core.search_sigmas);
  EXPECT_EQ(t.search_min_m, core.search_min_m);
  EXPECT_EQ(t.search_tie_ratio, core.search_tie_ratio);
  EXPECT_DOUBLE_EQ(t.turn_sigma_rad, core.turn_sigma_rad);
  const WallExtractionOptions w = ToWallExtractionOptions(c);
  const WallExtractionOptions core_w;
  EXPECT_EQ(w.max_normal_up, core_w.max_normal_up);
  EXPECT_EQ(w.density_per_m2, core_w.density_per_m2);
  EXPECT_EQ(w.seed, core_w.seed);
  EXPECT_EQ(w.max_edge_m, core_w.max_edge_m);
}

TEST(ConfigTest, ValuesAreParsedAndConverted) {
  v1::FloorposedConfig c;
  std::string error;
  ASSERT_TRUE(ParseConfig(R"(
      headset_frame: "zup"
      plan_path: "/srv/plans/floor1.geojson"
      walls { density_per_m2: 80 seed: 9 }
      icp { max_iterations: 30 levels: 1 }
      tracking { min_points: 100 }
  )",
                          &c, &error))
      << error;
  EXPECT_EQ(c.headset_frame(), "zup");
  EXPECT_EQ(ToWallExtractionOptions(c).density_per_m2, 80.0);
  EXPECT_EQ(ToWallExtractionOptions(c).seed, 9u);
  EXPECT_EQ(ToTrackerOptions(c).icp.max_iterations, 30u);
  EXPECT_EQ(ToTrackerOptions(c).icp.levels, 1u);
  EXPECT_EQ(ToTrackerOptions(c).min_points, 100u);
  EXPECT_EQ(c.walls().max_edge_m(), 10.0);  // untouched fields keep their defaults
}

TEST(ConfigTest, UnknownFieldIsAnErrorNamingTheLine) {
  v1::FloorposedConfig c;
  std::string error;
  EXPECT_FALSE(
      ParseConfig("headset_frame: \"unity\"\nlog_level: \"info\"\ndensity: 5\n", &c, &error));
  EXPECT_THAT(error, HasSubstr("line 3"));
  EXPECT_THAT(error, HasSubstr("density"));

  EXPECT_FALSE(ParseConfig("walls {\n  max_edge: 3\n}\n", &c, &error));
  EXPECT_THAT(error, HasSubstr("line 2"));
}

TEST(ConfigTest, SyntaxAndTypeErrors) {
  v1::FloorposedConfig c;
  std::string error;
  EXPECT_FALSE(ParseConfig("walls { density_per_m2: 5\n", &c, &error));  // unclosed
  EXPECT_FALSE(error.empty());
  EXPECT_FALSE(ParseConfig("icp { max_iterations: -3 }", &c, &error));  // unsigned
  EXPECT_THAT(error, HasSubstr("line 1"));
  EXPECT_FALSE(ParseConfig("status_period_s: \"soon\"", &c, &error));
  EXPECT_FALSE(error.empty());
}

TEST(ConfigTest, ValidateRejectsValuesTheSchemaCannot) {
  struct Case {
    const char* text;
    const char* error_part;
  };
  for (const Case& k : {
           Case{"headset_frame: \"left\"", "headset_frame"},
           Case{"headset_frame: \"\"", "headset_frame"},
           Case{"dds { domain_id: 300 }", "domain_id"},
           Case{"dds { device_id: \"\" }", "device_id"},
           Case{"walls { density_per_m2: 0 }", "density_per_m2"},
           Case{"walls { density_per_m2: nan }", "density_per_m2"},
           Case{"walls { max_normal_up: 1.5 }", "max_normal_up"},
           Case{"icp { max_correspondence_m: -1 }", "max_correspondence_m"},
           Case{"icp { levels: 20 }", "levels"},
           Case{"tracking { snapshot_voxel_m: 0 }", "snapshot_voxel_m"},
           Case{"tracking { max_ambiguity: 0 }", "max_ambiguity"},
           Case{"tracking { max_ambiguity: 1.5 }", "max_ambiguity"},
           Case{"tracking { refine_window_s: -1 }", "refine_window_s"},
           Case{"tracking { first_inlier_ratio: 1.1 }", "first_inlier_ratio"},
           Case{"tracking { searched_first_inlier_ratio: -0.1 }", "searched_first_inlier_ratio"},
           Case{"tracking { jump_clear_ratio: -0.5 }", "jump_clear_ratio"},
           Case{"tracking { jump_clear_inliers: 0 }", "jump_clear_inliers"},
           Case{"tracking { clear_ambiguity: 0.8 }", "clear_ambiguity"},
           Case{"registration { pick_tie_ratio: -0.1 }", "pick_tie_ratio"},
           Case{"registration { search_sigmas: -1 }", "search_sigmas"},
           Case{"registration { search_min_m: nan }", "search_min_m"},
           Case{"registration { search_tie_ratio: 2 }", "search_tie_ratio"},
           Case{"tracking { turn_sigma_deg: 0 }", "turn_sigma_deg"},
           Case{"tracking { drift_turn: -0.01 }", "drift_"},
           Case{"tracking { refine_window_s: inf }", "refine_window_s"},
           Case{"tracking { window_s: -5 }", "tracking.window_s"},
           Case{"tracking { global_check_min_points: 5 }", "global_check_min_points"},
           Case{"tracking { off_plan_margin_m: -1 }", "off_plan_margin_m"},
           Case{"tracking { global_place_min_inliers: 1.5 }", "global_place_min_inliers"},
           Case{"tracking { global_check_interval_s: 0 }", "global_check_interval_s"},
           Case{"tracking { off_plan_margin_m: nan }", "off_plan_margin_m"},
           Case{"tracking { global_unseen_reach_m: -1 }", "global_unseen_reach_m"},
           Case{"tracking { global_unseen_allowance: 1.5 }", "global_unseen_allowance"},
           Case{"tracking { global_alike_share: -0.5 }", "global_alike_share"},
           Case{"tracking { global_crowded_ratio: 2 }", "global_crowded_ratio"},
           Case{"tracking { global_twin_clear_ratio: 0 }", "global_twin_clear_ratio"},
           Case{"tracking { wheel_odometry { window_s: nan } }", "wheel_odometry.window_s"},
           Case{"tracking { wheel_odometry { drift_window: 5000 } }", "drift_window"},
           Case{"routes { body_radius_m: 0 }", "routes.body_radius_m"},
           Case{"routes { cell_m: 0.001 }", "cell_m"},
           Case{"routes { snap_m: nan }", "routes.snap_m"},
           Case{"explored { max_ray_m: -1 }", "explored.max_ray_m"},
           Case{"explored { publish_period_s: inf }", "explored.publish_period_s"},
           Case{"status_period_s: 0", "status_period_s"},
           Case{"log_level: \"loud\"", "log_level"},
       }) {
    SCOPED_TRACE(k.text);
    v1::FloorposedConfig c;
    std::string error;
    EXPECT_FALSE(ParseConfig(k.text, &c, &error));
    EXPECT_THAT(error, HasSubstr(k.error_part));
  }
  v1::FloorposedConfig c;
  c.set_headset_frame("Unity");  // names are case-sensitive
  EXPECT_THAT(ValidateConfig(c), HasSubstr("headset_frame"));
  c.set_headset_frame("zup");
  EXPECT_THAT(ValidateConfig(c), IsEmpty());
}

TEST(ConfigTest, WheelOdometryReplacesTheHeadsetsDriftAndWindows) {
  v1::FloorposedConfig c;
  std::string error;
  ASSERT_TRUE(ParseConfig("tracking { window_s: 30 wheel_odometry { window_s: 4 } }", &c, &error))
      << error;
  const v1::FloorposedConfig headset = ForOdometry(c, v1::HeadsetPose::VISUAL_INERTIAL);
  EXPECT_EQ(headset.tracking().window_s(), 30);
  EXPECT_EQ(headset.tracking().drift_window(), 0u);
  EXPECT_EQ(headset.tracking().refine_window_s(), 20);
  const v1::FloorposedConfig wheel = ForOdometry(c, v1::HeadsetPose::WHEEL);
  EXPECT_EQ(wheel.tracking().window_s(), 4);
  EXPECT_EQ(wheel.tracking().drift_window(), 9u);
  EXPECT_EQ(wheel.tracking().refine_window_s(), 3);
  EXPECT_EQ(wheel.tracking().confirm_walk_m(), 3);
  EXPECT_EQ(headset.tracking().confirm_walk_m(), 10);
  EXPECT_EQ(headset.tracking().jump_clear_ratio(), 0);
  EXPECT_EQ(ToTrackerOptions(wheel).jump_clear_ratio, 0.6);
  EXPECT_FALSE(headset.tracking().search_recent());
  EXPECT_TRUE(wheel.tracking().search_recent());
  EXPECT_EQ(ToTrackerOptions(wheel).filter.drift_window, 9);
  EXPECT_EQ(wheel.tracking().drift_heading_deg(), headset.tracking().drift_heading_deg());
  // The belief's drift and window: a wheel's (tracking.mcl.wheel), else a headset's.
  const tracking::MclOptions mcl_headset = ToMclOptions(headset);
  const tracking::MclOptions mcl_wheel = ToMclOptions(wheel);
  EXPECT_DOUBLE_EQ(mcl_headset.motion.heading_rad_per_sqrt_m, 0.3 * M_PI / 180);
  EXPECT_DOUBLE_EQ(mcl_wheel.motion.heading_rad_per_sqrt_m, 4.0 * M_PI / 180);
  EXPECT_DOUBLE_EQ(mcl_headset.motion.heading_per_turn, 0.005);
  EXPECT_DOUBLE_EQ(mcl_wheel.motion.heading_per_turn, 0.05);
  EXPECT_DOUBLE_EQ(mcl_headset.window_s, 20);
  EXPECT_DOUBLE_EQ(mcl_wheel.window_s, 4);
  EXPECT_DOUBLE_EQ(mcl_wheel.motion.position_m_per_sqrt_m,
                   mcl_headset.motion.position_m_per_sqrt_m);
}

// Every field of a message type and of its sub-messages, depth first.
void FieldNames(const pb::Descriptor* d, std::vector<const pb::FieldDescriptor*>* out) {
  for (int i = 0; i < d->field_count(); ++i) {
    const pb::FieldDescriptor* f = d->field(i);
    out->push_back(f);
    if (f->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE) FieldNames(f->message_type(), out);
  }
}

TEST(ConfigTest, ResolvedTextHasEveryOption) {
  const std::string text = ResolvedConfigText(v1::FloorposedConfig());
  EXPECT_THAT(text, HasSubstr("density_per_m2: 50"));
  EXPECT_THAT(text, HasSubstr("headset_frame: \"unity\""));
  EXPECT_THAT(text, HasSubstr("plan_path: \"\""));
  std::vector<const pb::FieldDescriptor*> fields;
  FieldNames(v1::FloorposedConfig::descriptor(), &fields);
  ASSERT_GT(fields.size(), 30u);
  for (const auto* f : fields) {
    const std::string key =
        f->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE ? f->name() + " {" : f->name() + ":";
    EXPECT_THAT(text, HasSubstr(key)) << "option " << f->full_name() << " missing";
  }
}

TEST(ConfigTest, ResolvedTextParsesBackToTheSameConfig) {
  v1::FloorposedConfig c;
  std::string error;
  ASSERT_TRUE(ParseConfig("walls { density_per_m2: 75 }\nlog_level: \"debug\"", &c, &error));
  const std::string text = ResolvedConfigText(c);
  EXPECT_THAT(text, HasSubstr("density_per_m2: 75"));
  v1::FloorposedConfig back;
  ASSERT_TRUE(ParseConfig(text, &back, &error)) << error << "\n" << text;
  EXPECT_EQ(back.walls().density_per_m2(), 75.0);
  EXPECT_EQ(back.log_level(), "debug");
  EXPECT_EQ(ResolvedConfigText(back), text);
}

using ConfigFileTest = testing::TempDirTest;

TEST_F(ConfigFileTest, LoadConfig) {
  v1::FloorposedConfig c;
  std::string error;
  c.set_log_level("error");
  ASSERT_TRUE(LoadConfig("", &c, &error));  // no file: the defaults
  EXPECT_EQ(c.log_level(), "info");

  ASSERT_TRUE(LoadConfig(Write("good.pbtxt", "log_level: \"warn\"\n"), &c, &error)) << error;
  EXPECT_EQ(c.log_level(), "warn");

  const std::string bad = Write("bad.pbtxt", "\n\nno_such_option: 1\n");
  EXPECT_FALSE(LoadConfig(bad, &c, &error));
  EXPECT_THAT(error, HasSubstr(bad));       // names the file...
  EXPECT_THAT(error, HasSubstr("line 3"));  // ...and the line

  EXPECT_FALSE(LoadConfig(Path("missing.pbtxt"), &c, &error));
  EXPECT_THAT(error, HasSubstr("missing.pbtxt"));
}

}  // namespace
}  // namespace floorpose::platform
