#include "core/sim/demo_walk.h"

#include <cmath>
#include <map>
#include <set>

#include "core/random.h"

namespace floorpose::sim {
namespace {

struct Piece {
  Eigen::Vector2d a, b;
};

// Wall pieces of about piece_m along every segment.
std::vector<Piece> CutPieces(const FloorPlan& plan, double piece_m) {
  std::vector<Piece> out;
  for (const Segment& s : plan.segments) {
    const int n = std::max(1, static_cast<int>(std::ceil(s.Length() / piece_m)));
    for (int i = 0; i < n; ++i)
      out.push_back({s.a + (s.b - s.a) * (double(i) / n), s.a + (s.b - s.a) * (double(i + 1) / n)});
  }
  return out;
}

int64_t ChunkKey(const Eigen::Vector2d& p, double chunk_m) {
  const auto ix = static_cast<int64_t>(std::floor(p.x() / chunk_m));
  const auto iy = static_cast<int64_t>(std::floor(p.y() / chunk_m));
  return (ix + (1 << 20)) * (1 << 21) + (iy + (1 << 20));
}

}  // namespace

DemoWalk SimulateDemoWalk(const FloorPlan& plan, const std::vector<Eigen::Vector2d>& waypoints,
                          const DemoWalkOptions& o) {
  DemoWalk walk;
  if (waypoints.size() < 2) return walk;
  SplitMix64 rng(o.seed);
  const std::vector<Piece> pieces = CutPieces(plan, o.piece_m);

  // Ground truth: constant speed along the polyline, heading along the motion.
  std::vector<Pose2> truth;
  {
    const double step = o.speed_mps * o.pose_period_s;
    size_t leg = 0;
    double along = 0.0;
    Eigen::Vector2d pos = waypoints[0];
    while (leg + 1 < waypoints.size()) {
      const Eigen::Vector2d d = waypoints[leg + 1] - waypoints[leg];
      const double len = d.norm();
      if (along >= len) {
        along -= len;
        ++leg;
        continue;
      }
      pos = waypoints[leg] + d * (along / len);
      truth.push_back({pos, std::atan2(d.y(), d.x()), 1.6});
      along += step;
    }
    truth.push_back({waypoints.back(), truth.empty() ? 0.0 : truth.back().heading, 1.6});
  }

  // SLAM: integrate the true body-frame increments with a scale error and heading bias.
  Se2 T_slam_plan{o.initial_theta_rad, o.initial_offset_m};
  walk.T_slam_plan_initial = T_slam_plan;
  Pose2 slam = Apply(T_slam_plan, truth[0]);

  std::map<int64_t, std::set<size_t>> chunk_pieces;  // pieces seen per chunk
  std::map<int64_t, double> chunk_emitted_s;
  std::map<int64_t, uint64_t> chunk_ids;
  std::map<int64_t, Se2> chunk_frame;  // T_slam_plan when the chunk was last meshed
  std::set<int64_t> dirty;

  for (size_t k = 0; k < truth.size(); ++k) {
    if (k > 0) {
      const Pose2& a = truth[k - 1];
      const Pose2& b = truth[k];
      const Eigen::Vector2d body = Se2{a.heading, a.position}.Inverse() * b.position;
      const double dtheta = WrapAngle(b.heading - a.heading);
      walk.length_m += body.norm();
      const Eigen::Vector2d slam_body = body * (1.0 + o.scale_error);
      const double slam_dtheta = dtheta + o.heading_drift_rad_per_m * body.norm();
      slam.position += Se2{slam.heading, {0, 0}}.R() * slam_body;
      slam.heading = WrapAngle(slam.heading + slam_dtheta);
      slam.z = b.z;
      // The slam frame as seen from the plan now: slam = T_slam_plan * truth.
      T_slam_plan.theta = WrapAngle(slam.heading - b.heading);
      T_slam_plan.t = slam.position - T_slam_plan.R() * b.position;
    }
    SimStep step;
    step.stamp_ns = static_cast<int64_t>(std::llround(k * o.pose_period_s * 1e9));
    step.true_plan = truth[k];
    step.slam = slam;

    // What the headset sees now: wall pieces within range.
    for (size_t i = 0; i < pieces.size(); ++i) {
      const Eigen::Vector2d mid = 0.5 * (pieces[i].a + pieces[i].b);
      if ((mid - truth[k].position).norm() > o.sensor_range_m) continue;
      const int64_t key = ChunkKey(mid, o.chunk_m);
      if (chunk_pieces[key].insert(i).second) dirty.insert(key);
    }
    const double now_s = k * o.pose_period_s;
    if (k % o.poses_per_mesh_update == 0) {
      for (auto it = dirty.begin(); it != dirty.end();) {
        const int64_t key = *it;
        const bool known = chunk_ids.count(key) > 0;
        if (known && now_s - chunk_emitted_s[key] < o.update_after_s) {
          ++it;
          continue;
        }
        if (!known) chunk_ids[key] = chunk_ids.size() + 1;
        chunk_emitted_s[key] = now_s;
        chunk_frame[key] = T_slam_plan;
        SimMesh mesh;
        mesh.id = chunk_ids[key];
        mesh.change = known ? MeshChange::kUpdated : MeshChange::kAdded;
        auto vertex = [&](const Eigen::Vector2d& p_plan, double z) {
          const Eigen::Vector2d p = T_slam_plan * p_plan;
          mesh.vertices_slam.emplace_back(
              static_cast<float>(p.x() + o.vertex_noise_m * rng.Gaussian()),
              static_cast<float>(p.y() + o.vertex_noise_m * rng.Gaussian()),
              static_cast<float>(z + o.vertex_noise_m * rng.Gaussian()));
          return static_cast<uint32_t>(mesh.vertices_slam.size() - 1);
        };
        Eigen::Vector2d centre = Eigen::Vector2d::Zero();
        for (size_t i : chunk_pieces[key]) {
          const Piece& p = pieces[i];
          centre += 0.5 * (p.a + p.b);
          // A quad from floor to wall height, split at mid height: four triangles.
          const double h = o.wall_height_m;
          const uint32_t a0 = vertex(p.a, 0), b0 = vertex(p.b, 0);
          const uint32_t a1 = vertex(p.a, h / 2), b1 = vertex(p.b, h / 2);
          const uint32_t a2 = vertex(p.a, h), b2 = vertex(p.b, h);
          for (uint32_t t : {a0, b0, b1, a0, b1, a1, a1, b1, b2, a1, b2, a2})
            mesh.triangles.push_back(t);
        }
        // A patch of floor near the walls: horizontal, to be filtered out.
        centre /= static_cast<double>(chunk_pieces[key].size());
        const uint32_t f0 = vertex(centre + Eigen::Vector2d(-0.5, -0.5), 0);
        const uint32_t f1 = vertex(centre + Eigen::Vector2d(0.5, -0.5), 0);
        const uint32_t f2 = vertex(centre + Eigen::Vector2d(0.5, 0.5), 0);
        const uint32_t f3 = vertex(centre + Eigen::Vector2d(-0.5, 0.5), 0);
        for (uint32_t t : {f0, f1, f2, f0, f2, f3}) mesh.triangles.push_back(t);
        step.meshes.push_back(std::move(mesh));
        it = dirty.erase(it);
      }
    }
    walk.steps.push_back(std::move(step));
  }

  // The wall pick: the plan wall nearest the start, its normal facing the wearer.
  const Eigen::Vector2d start = truth[0].position;
  double best = 1e300;
  for (const Segment& s : plan.segments) {
    const Eigen::Vector2d c = ClosestPointOnSegment(s, start);
    if ((c - start).norm() < best) {
      best = (c - start).norm();
      walk.pick.plan_point = c;
      walk.pick.plan_normal = s.Normal();
      if (walk.pick.plan_normal.dot(start - c) < 0) walk.pick.plan_normal = -walk.pick.plan_normal;
    }
  }
  const Se2& T0 = walk.T_slam_plan_initial;
  const double normal_error = o.pick_normal_error_rad * rng.Gaussian();
  walk.pick.slam_point = T0 * walk.pick.plan_point +
                         o.pick_point_error_m * Eigen::Vector2d(rng.Gaussian(), rng.Gaussian());
  walk.pick.slam_normal = Se2{T0.theta + normal_error, {0, 0}}.R() * walk.pick.plan_normal;
  return walk;
}

}  // namespace floorpose::sim
