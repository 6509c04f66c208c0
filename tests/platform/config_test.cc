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
  EXPECT_EQ(c.walls().window_max_points(), 20000u);
  EXPECT_EQ(c.dds().device_id(), "hololens-1");
  EXPECT_EQ(c.log_level(), "info");
  EXPECT_THAT(ValidateConfig(c), IsEmpty());
}

TEST(ConfigTest, ProtoDefaultsMatchTheCoreDefaults) {
  // The core's option structs and the config schema each carry defaults; they must
  // agree, or the daemon and the offline tools would run different algorithms.
  const v1::FloorposedConfig c;
  const tracking::MclOptions t = ToMclOptions(c);
  const tracking::MclOptions core;
  EXPECT_EQ(t.icp.max_iterations, core.icp.max_iterations);
  EXPECT_EQ(t.icp.levels, core.icp.levels);
  EXPECT_EQ(t.icp.reject_sigma, core.icp.reject_sigma);
  EXPECT_EQ(t.icp.max_correspondence_m, core.icp.max_correspondence_m);
  EXPECT_EQ(t.icp.converge_translation_m, core.icp.converge_translation_m);
  EXPECT_EQ(t.icp.converge_rotation_rad, core.icp.converge_rotation_rad);
  EXPECT_EQ(t.icp.cauchy_scale_factor, core.icp.cauchy_scale_factor);
  EXPECT_EQ(t.icp.inlier_threshold_m, core.icp.inlier_threshold_m);
  EXPECT_EQ(t.icp.degeneracy_ratio, core.icp.degeneracy_ratio);
  // Angles are configured in degrees; 1e-12 rad is far below anything they tell apart.
  EXPECT_EQ(t.motion.position_m_per_sqrt_m, core.motion.position_m_per_sqrt_m);
  EXPECT_NEAR(t.motion.heading_rad_per_sqrt_m, core.motion.heading_rad_per_sqrt_m, 1e-12);
  EXPECT_EQ(t.motion.heading_per_turn, core.motion.heading_per_turn);
  EXPECT_EQ(t.motion.lost_after_s, core.motion.lost_after_s);
  EXPECT_EQ(t.motion.relocalization_m, core.motion.relocalization_m);
  EXPECT_NEAR(t.motion.relocalization_rad, core.motion.relocalization_rad, 1e-12);
  EXPECT_EQ(t.motion.through_wall, core.motion.through_wall);
  EXPECT_EQ(t.measurement.sigma_m, core.measurement.sigma_m);
  EXPECT_EQ(t.measurement.clutter, core.measurement.clutter);
  EXPECT_EQ(t.measurement.independent_points, core.measurement.independent_points);
  EXPECT_EQ(t.window_s, core.window_s);
  EXPECT_EQ(t.update_interval_s, core.update_interval_s);
  EXPECT_EQ(t.samples.min_samples, core.samples.min_samples);
  EXPECT_EQ(t.samples.max_samples, core.samples.max_samples);
  EXPECT_EQ(t.pick_sigma_m, core.pick_sigma_m);
  EXPECT_NEAR(t.pick_sigma_rad, core.pick_sigma_rad, 1e-12);
  EXPECT_EQ(t.recovery.lost_s, core.recovery.lost_s);
  EXPECT_EQ(t.recovery.start_doubt, core.recovery.start_doubt);
  EXPECT_EQ(t.recovery.search_share, core.recovery.search_share);
  EXPECT_EQ(t.recovery.search_interval_s, core.recovery.search_interval_s);
  EXPECT_EQ(t.publish.reliable, core.publish.reliable);
  EXPECT_EQ(t.publish.degraded, core.publish.degraded);
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
      tracking { samples { max_samples: 1500 } }
  )",
                          &c, &error))
      << error;
  EXPECT_EQ(c.headset_frame(), "zup");
  EXPECT_EQ(ToWallExtractionOptions(c).density_per_m2, 80.0);
  EXPECT_EQ(ToWallExtractionOptions(c).seed, 9u);
  EXPECT_EQ(ToMclOptions(c).icp.max_iterations, 30u);
  EXPECT_EQ(ToMclOptions(c).icp.levels, 1u);
  EXPECT_EQ(ToMclOptions(c).samples.max_samples, 1500u);
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
           Case{"walls { voxel_m: 0 }", "walls.voxel_m"},
           Case{"tracking { motion { through_wall: 0 } }", "through_wall"},
           Case{"tracking { measurement { clutter: 1 } }", "clutter"},
           Case{"tracking { measurement { window_s: nan } }", "measurement.window_s"},
           Case{"tracking { wheel { window_s: -1 } }", "wheel.window_s"},
           Case{"tracking { recovery { start_doubt: 1 } }", "start_doubt"},
           Case{"tracking { samples { min_samples: 10 max_samples: 5 } }", "samples"},
           Case{"tracking { publish { reliable: 0.4 } }", "publish"},
           Case{"tracking { motion { heading_per_turn: -1 } }", "heading_per_turn"},
           Case{"routes { body_radius_m: 0 }", "routes.body_radius_m"},
           Case{"routes { cell_m: 0.001 }", "cell_m"},
           Case{"routes { snap_m: nan }", "routes.snap_m"},
           Case{"explored { max_ray_m: -1 }", "explored.max_ray_m"},
           Case{"explored { publish_period_s: inf }", "explored.publish_period_s"},
           Case{"status_period_s: 0", "status_period_s"},
           Case{"limits { search_cpu: -0.1 }", "search_cpu"},
           Case{"limits { search_cpu: nan }", "search_cpu"},
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

TEST(ConfigTest, AWheelsDriftReplacesTheHeadsets) {
  v1::FloorposedConfig c;
  std::string error;
  ASSERT_TRUE(ParseConfig("tracking { wheel { window_s: 4 } }", &c, &error)) << error;
  const v1::FloorposedConfig headset = ForOdometry(c, v1::HeadsetPose::VISUAL_INERTIAL);
  const v1::FloorposedConfig wheel = ForOdometry(c, v1::HeadsetPose::WHEEL);
  // The belief's drift and window: a wheel's (tracking.wheel), else a headset's.
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
