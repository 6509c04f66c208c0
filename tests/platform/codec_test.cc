// The daemon's input boundary: protobuf payloads in, validated slam-frame data out.
// Every bad payload is refused with a reason; nothing throws or aborts.
#include "platform/codec.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <google/protobuf/descriptor.h>

#include <cmath>
#include <limits>

#include "core/random.h"
#include "core/wall_extractor.h"
#include "tests/test_util.h"

namespace floorpose::platform {
namespace {

using ::testing::HasSubstr;
using ::testing::IsEmpty;

constexpr auto kUnity = HeadsetFrame::kUnityLeftHandedYUp;
const float kNaN = std::numeric_limits<float>::quiet_NaN();

// A Unity-frame wall 3 m wide and 2.5 m high in the plane x = 2 (y up), two triangles.
v1::MeshDelta WallDelta() {
  v1::MeshDelta m;
  m.set_mesh_id(17);
  m.set_change(v1::MeshDelta::ADDED);
  m.set_stamp_ns(123456789);
  for (float v : {2.f, 0.f, 0.f, 2.f, 0.f, 3.f, 2.f, 2.5f, 3.f, 2.f, 2.5f, 0.f}) m.add_vertices(v);
  for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.add_triangles(i);
  return m;
}

std::string Decode(const v1::MeshDelta& m, DecodedMesh* out,
                   const v1::LimitsConfig& limits = v1::LimitsConfig()) {
  return DecodeMeshDelta(m.SerializeAsString(), kUnity, limits, out);
}

TEST(DecodeMeshDeltaTest, GoodDeltaInSlamFrame) {
  DecodedMesh out;
  ASSERT_THAT(Decode(WallDelta(), &out), IsEmpty());
  EXPECT_EQ(out.mesh_id, 17u);
  EXPECT_EQ(out.change, v1::MeshDelta::ADDED);
  EXPECT_EQ(out.stamp_ns, 123456789);
  ASSERT_EQ(out.vertices.size(), 4u);
  EXPECT_EQ(out.unusable_vertices, 0u);
  // Unity (x, y, z) -> slam (x, z, y).
  EXPECT_EQ(out.vertices[2], Eigen::Vector3f(2, 3, 2.5));
  EXPECT_EQ(out.triangles, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));

  // The decoded wall is vertical in slam, so the extractor samples it (x = 2, normal
  // along x).
  WallExtractionOptions options;
  options.density_per_m2 = 100;
  const auto points = ExtractWallPoints({&out.vertices, &out.triangles}, out.mesh_id, options);
  ASSERT_EQ(points.size(), 750u);  // 7.5 m^2
  for (const WallPoint& w : points) {
    EXPECT_NEAR(w.p.x(), 2.0f, 1e-5f);
    EXPECT_NEAR(std::abs(w.n.x()), 1.0f, 1e-6f);
  }
}

TEST(DecodeMeshDeltaTest, MeshToWorldIsAppliedInSlam) {
  // Random rigid mesh-to-world transforms (Unity frame, row-major): each decoded vertex
  // is the converted world position of the mesh vertex.
  SplitMix64 rng(61);
  for (int i = 0; i < 20; ++i) {
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    T.topLeftCorner<3, 3>() = testing::RandomRotation(rng).toRotationMatrix();
    T.topRightCorner<3, 1>() = testing::RandomVector3(rng, -10, 10);
    v1::MeshDelta m = WallDelta();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) m.add_mesh_to_world(static_cast<float>(T(r, c)));
    DecodedMesh out;
    ASSERT_THAT(Decode(m, &out), IsEmpty());
    const Eigen::Matrix4d Tf = T.cast<float>().cast<double>();  // as sent
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector4d v(m.vertices(3 * k), m.vertices(3 * k + 1), m.vertices(3 * k + 2), 1);
      const Eigen::Vector3d world = (Tf * v).head<3>();
      const Eigen::Vector3d want(world.x(), world.z(), world.y());
      EXPECT_LT((out.vertices[static_cast<size_t>(k)].cast<double>() - want).norm(), 1e-5);
    }
  }
}

TEST(DecodeMeshDeltaTest, RejectsMalformedBytes) {
  DecodedMesh out;
  const v1::LimitsConfig limits;
  const std::string good = WallDelta().SerializeAsString();
  // Cut inside the packed vertex array, a length running past the end, and a field
  // number of 0 (invalid in protobuf).
  for (const std::string& bad : {good.substr(0, good.size() - 5),
                                 std::string("\x2a\x7f\x01\x02", 4), std::string("\x02\x00", 2),
                                 std::string("\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff", 11)}) {
    EXPECT_THAT(DecodeMeshDelta(bad, kUnity, limits, &out), HasSubstr("malformed"));
  }
}

TEST(DecodeMeshDeltaTest, RejectsUnknownAndUnspecifiedChange) {
  // An enum value this build does not know, set through reflection as a newer headset
  // app might send it.
  v1::MeshDelta m = WallDelta();
  const auto* field = m.GetDescriptor()->FindFieldByName("change");
  ASSERT_NE(field, nullptr);
  m.GetReflection()->SetEnumValue(&m, field, 7);
  DecodedMesh out;
  EXPECT_THAT(Decode(m, &out), HasSubstr("unknown change 7"));

  m.set_change(v1::MeshDelta::CHANGE_UNSPECIFIED);
  EXPECT_THAT(Decode(m, &out), HasSubstr("unknown change 0"));
}

TEST(DecodeMeshDeltaTest, RejectsBadGeometry) {
  DecodedMesh out;
  v1::MeshDelta m = WallDelta();
  m.add_vertices(1.0f);  // 13 floats
  EXPECT_THAT(Decode(m, &out), HasSubstr("not a multiple of 3"));

  m = WallDelta();
  m.add_triangles(0);
  EXPECT_THAT(Decode(m, &out), HasSubstr("index array not a multiple of 3"));

  v1::LimitsConfig limits;
  limits.set_max_vertices_per_mesh(3);
  EXPECT_THAT(Decode(WallDelta(), &out, limits), HasSubstr("4 vertices over the limit of 3"));
  limits = v1::LimitsConfig();
  limits.set_max_triangles_per_mesh(1);
  EXPECT_THAT(Decode(WallDelta(), &out, limits), HasSubstr("triangles over the limit"));
}

TEST(DecodeMeshDeltaTest, RejectsBadMeshToWorld) {
  DecodedMesh out;
  auto with_matrix = [](std::vector<float> values) {
    v1::MeshDelta m = WallDelta();
    for (float v : values) m.add_mesh_to_world(v);
    return m;
  };
  const std::vector<float> identity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  ASSERT_THAT(Decode(with_matrix(identity), &out), IsEmpty());

  std::vector<float> projective = identity;
  projective[14] = 0.5f;  // last row 0 0 0.5 1
  EXPECT_THAT(Decode(with_matrix(projective), &out), HasSubstr("not affine"));

  std::vector<float> non_finite = identity;
  non_finite[3] = kNaN;
  EXPECT_THAT(Decode(with_matrix(non_finite), &out), HasSubstr("non-finite mesh-to-world"));
  non_finite[3] = std::numeric_limits<float>::infinity();
  EXPECT_THAT(Decode(with_matrix(non_finite), &out), HasSubstr("non-finite mesh-to-world"));

  EXPECT_THAT(Decode(with_matrix({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}), &out),
              HasSubstr("needs 16 values, got 12"));
}

TEST(DecodeMeshDeltaTest, NonFiniteAndHugeVerticesAreMarkedUnusable) {
  v1::MeshDelta m = WallDelta();
  m.set_vertices(0, kNaN);
  m.set_vertices(4, 2e4f);  // beyond the default 10 km limit
  m.set_vertices(8, std::numeric_limits<float>::infinity());
  DecodedMesh out;
  ASSERT_THAT(Decode(m, &out), IsEmpty());
  EXPECT_EQ(out.unusable_vertices, 3u);
  EXPECT_FALSE(out.vertices[0].allFinite());
  EXPECT_FALSE(out.vertices[1].allFinite());
  EXPECT_FALSE(out.vertices[2].allFinite());
  EXPECT_TRUE(out.vertices[3].allFinite());
  // The extractor counts their triangles as degenerate and carries on.
  WallExtractionReport report;
  EXPECT_TRUE(ExtractWallPoints({&out.vertices, &out.triangles}, 1, {}, &report).empty());
  EXPECT_EQ(report.degenerate_triangles, 2u);
}

TEST(DecodeMeshDeltaTest, RemovedNeedsNoGeometry) {
  v1::MeshDelta m;
  m.set_mesh_id(9);
  m.set_change(v1::MeshDelta::REMOVED);
  m.set_stamp_ns(5);
  DecodedMesh out;
  out.vertices.resize(3);  // stale content must be cleared
  ASSERT_THAT(Decode(m, &out), IsEmpty());
  EXPECT_EQ(out.mesh_id, 9u);
  EXPECT_EQ(out.change, v1::MeshDelta::REMOVED);
  EXPECT_EQ(out.stamp_ns, 5);
  EXPECT_TRUE(out.vertices.empty());
  EXPECT_TRUE(out.triangles.empty());
}

// Stamps near the int64 limits would overflow the engine's stamp arithmetic (found by
// tests/fuzz/mesh_ingest_fuzzer): refused at the boundary.
TEST(DecodeMeshDeltaTest, RejectsStampsNearTheInt64Limits) {
  DecodedMesh out;
  v1::MeshDelta m = WallDelta();
  for (int64_t stamp : {std::numeric_limits<int64_t>::min(), -(int64_t{1} << 62), int64_t{1} << 62,
                        std::numeric_limits<int64_t>::max()}) {
    m.set_stamp_ns(stamp);
    EXPECT_THAT(Decode(m, &out), HasSubstr("stamp_ns " + std::to_string(stamp) + " out of range"));
  }
  m.set_change(v1::MeshDelta::REMOVED);  // its stamp moves the scheduling clock too
  EXPECT_THAT(Decode(m, &out), HasSubstr("out of range"));
  m.set_stamp_ns(-5);  // negative stamps of a sane size are a clock's business
  EXPECT_THAT(Decode(m, &out), IsEmpty());
}

v1::HeadsetPose GoodPose() {
  v1::HeadsetPose p;
  p.set_stamp_ns(42);
  p.mutable_position()->set_x(1);
  p.mutable_position()->set_y(1.6);
  p.mutable_position()->set_z(3);
  p.mutable_orientation()->set_w(1);
  p.set_tracking(v1::HeadsetPose::TRACKING_OK);
  return p;
}

std::string Decode(const v1::HeadsetPose& p, DecodedPose* out) {
  return DecodeHeadsetPose(p.SerializeAsString(), kUnity, v1::LimitsConfig(), out);
}

TEST(DecodeHeadsetPoseTest, GoodPose) {
  DecodedPose out;
  ASSERT_THAT(Decode(GoodPose(), &out), IsEmpty());
  EXPECT_EQ(out.stamp_ns, 42);
  EXPECT_EQ(out.tracking, v1::HeadsetPose::TRACKING_OK);
  EXPECT_EQ(out.odometry, v1::HeadsetPose::VISUAL_INERTIAL);  // unset: a headset's SLAM
  v1::HeadsetPose wheel = GoodPose();
  wheel.set_odometry(v1::HeadsetPose::WHEEL);
  ASSERT_THAT(Decode(wheel, &out), IsEmpty());
  EXPECT_EQ(out.odometry, v1::HeadsetPose::WHEEL);
  EXPECT_EQ(out.pose_slam.position, Eigen::Vector2d(1, 3));
  EXPECT_DOUBLE_EQ(out.pose_slam.z, 1.6);
  EXPECT_NEAR(out.pose_slam.heading, M_PI / 2, 1e-12);  // Unity forward is slam +y
}

TEST(DecodeHeadsetPoseTest, RejectsBadPoses) {
  DecodedPose out;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  v1::HeadsetPose p = GoodPose();
  p.mutable_position()->set_y(nan);
  EXPECT_THAT(Decode(p, &out), HasSubstr("non-finite"));

  p = GoodPose();
  p.mutable_orientation()->set_x(nan);
  EXPECT_THAT(Decode(p, &out), HasSubstr("non-finite"));

  p = GoodPose();
  p.mutable_orientation()->set_w(2);
  EXPECT_THAT(Decode(p, &out), HasSubstr("not a unit quaternion"));
  p.mutable_orientation()->set_w(0);  // the all-zero quaternion
  EXPECT_THAT(Decode(p, &out), HasSubstr("not a unit quaternion"));

  p = GoodPose();
  p.mutable_position()->set_x(-2e4);
  EXPECT_THAT(Decode(p, &out), HasSubstr("position beyond"));

  p = GoodPose();
  p.set_stamp_ns(std::numeric_limits<int64_t>::min());
  EXPECT_THAT(Decode(p, &out), HasSubstr("stamp_ns -9223372036854775808 out of range"));

  p = GoodPose();
  p.GetReflection()->SetEnumValue(&p, p.GetDescriptor()->FindFieldByName("tracking"), 9);
  EXPECT_THAT(Decode(p, &out), HasSubstr("unknown tracking state 9"));

  p = GoodPose();
  p.GetReflection()->SetEnumValue(&p, p.GetDescriptor()->FindFieldByName("odometry"), 7);
  EXPECT_THAT(Decode(p, &out), HasSubstr("unknown odometry 7"));

  const std::string good = GoodPose().SerializeAsString();
  EXPECT_THAT(DecodeHeadsetPose(good.substr(0, good.size() - 3), kUnity, {}, &out),
              HasSubstr("malformed"));
}

TEST(DecodeHeadsetPoseTest, SlightlyOffUnitQuaternionIsAccepted) {
  v1::HeadsetPose p = GoodPose();
  p.mutable_orientation()->set_w(1.005);  // float round trips on the headset
  DecodedPose out;
  EXPECT_THAT(Decode(p, &out), IsEmpty());
}

TEST(DecodeCommandTest, NeedsACommand) {
  v1::Command c;
  c.set_request_id(3);
  v1::Command out;
  EXPECT_THAT(DecodeCommand(c.SerializeAsString(), &out), HasSubstr("without a command"));
  c.mutable_flip();
  EXPECT_THAT(DecodeCommand(c.SerializeAsString(), &out), IsEmpty());
  EXPECT_TRUE(out.has_flip());
  EXPECT_EQ(out.request_id(), 3u);
  EXPECT_THAT(DecodeCommand(std::string("\x0a\x05\x01", 3), &out), HasSubstr("malformed"));
}

TEST(DecodeFuzzTest, RandomBytesNeverCrash) {
  // Seeded random mutations of good payloads: every decode returns, with an error or
  // with validated output.
  SplitMix64 rng(62);
  const std::string mesh = WallDelta().SerializeAsString();
  const std::string pose = GoodPose().SerializeAsString();
  const v1::LimitsConfig limits;
  int rejected = 0;
  for (int i = 0; i < 3000; ++i) {
    std::string m = i % 2 ? mesh : pose;
    const int edits = 1 + static_cast<int>(rng.Next() % 3);
    for (int e = 0; e < edits; ++e) {
      const size_t at = rng.Next() % m.size();
      if (rng.Next() % 4 == 0)
        m.resize(at);
      else
        m[at] = static_cast<char>(rng.Next() & 0xff);
      if (m.empty()) break;
    }
    DecodedMesh dm;
    DecodedPose dp;
    const std::string mesh_error = DecodeMeshDelta(m, kUnity, limits, &dm);
    const std::string pose_error = DecodeHeadsetPose(m, kUnity, limits, &dp);
    if (mesh_error.empty()) {
      // Every vertex is usable (finite, within the limit) or marked NaN and counted.
      size_t unusable = 0;
      for (const Eigen::Vector3f& v : dm.vertices) {
        if (!v.allFinite()) {
          ++unusable;
        } else {
          EXPECT_LE(v.cwiseAbs().maxCoeff(), limits.max_abs_coordinate_m());
        }
      }
      EXPECT_EQ(unusable, dm.unusable_vertices);
      // What the decoder passes, the extractor takes without a crash.
      for (const WallPoint& w : ExtractWallPoints({&dm.vertices, &dm.triangles}, 1, {}))
        EXPECT_TRUE(w.p.allFinite() && w.n.allFinite());
    } else {
      ++rejected;
    }
    if (pose_error.empty()) {
      EXPECT_TRUE(dp.pose_slam.position.allFinite());
      EXPECT_TRUE(std::isfinite(dp.pose_slam.heading));
    } else {
      ++rejected;
    }
  }
  EXPECT_GT(rejected, 0);
}

}  // namespace
}  // namespace floorpose::platform
