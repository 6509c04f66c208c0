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

// Ground truth: constant speed along the polyline, heading along the motion.
std::vector<Pose2> TruthAlong(const std::vector<Eigen::Vector2d>& waypoints, double step) {
  std::vector<Pose2> truth;
  size_t leg = 0;
  double along = 0.0;
  while (leg + 1 < waypoints.size()) {
    const Eigen::Vector2d d = waypoints[leg + 1] - waypoints[leg];
    const double len = d.norm();
    if (along >= len) {
      along -= len;
      ++leg;
      continue;
    }
    truth.push_back({waypoints[leg] + d * (along / len), std::atan2(d.y(), d.x()), 1.6});
    along += step;
  }
  truth.push_back({waypoints.back(), truth.empty() ? 0.0 : truth.back().heading, 1.6});
  return truth;
}

// The headset's spatial mesh: wall pieces seen are grouped in chunks of chunk_m, and a
// chunk that saw new pieces is meshed again (ADDED, then UPDATED) at most every
// update_after_s, in the SLAM frame of that moment.
class Mesher {
 public:
  Mesher(const std::vector<Piece>& pieces, const DemoWalkOptions& o) : pieces_(pieces), o_(o) {}

  // The pieces within sensor range of the wearer.
  void See(const Eigen::Vector2d& wearer_plan) {
    for (size_t i = 0; i < pieces_.size(); ++i) {
      const Eigen::Vector2d mid = 0.5 * (pieces_[i].a + pieces_[i].b);
      if ((mid - wearer_plan).norm() > o_.sensor_range_m) continue;
      const int64_t key = ChunkKey(mid, o_.chunk_m);
      if (chunk_pieces_[key].insert(i).second) dirty_.insert(key);
    }
  }

  // The chunks due at now_s, meshed in the SLAM frame T_slam_plan.
  void Emit(double now_s, const Se2& T_slam_plan, SplitMix64& rng, std::vector<SimMesh>* out) {
    for (auto it = dirty_.begin(); it != dirty_.end();) {
      const int64_t key = *it;
      const bool known = chunk_ids_.count(key) > 0;
      if (known && now_s - chunk_emitted_s_[key] < o_.update_after_s) {
        ++it;
        continue;
      }
      if (!known) chunk_ids_[key] = chunk_ids_.size() + 1;
      chunk_emitted_s_[key] = now_s;
      SimMesh mesh;
      mesh.id = chunk_ids_[key];
      mesh.change = known ? MeshChange::kUpdated : MeshChange::kAdded;
      Mesh(chunk_pieces_[key], T_slam_plan, rng, &mesh);
      out->push_back(std::move(mesh));
      it = dirty_.erase(it);
    }
  }

 private:
  // Each piece a quad from floor to wall height, split at mid height (four triangles), and
  // a patch of floor near the walls: horizontal, to be filtered out.
  void Mesh(const std::set<size_t>& pieces, const Se2& T_slam_plan, SplitMix64& rng,
            SimMesh* mesh) const {
    auto vertex = [&](const Eigen::Vector2d& p_plan, double z) {
      const Eigen::Vector2d p = T_slam_plan * p_plan;
      mesh->vertices_slam.emplace_back(
          static_cast<float>(p.x() + o_.vertex_noise_m * rng.Gaussian()),
          static_cast<float>(p.y() + o_.vertex_noise_m * rng.Gaussian()),
          static_cast<float>(z + o_.vertex_noise_m * rng.Gaussian()));
      return static_cast<uint32_t>(mesh->vertices_slam.size() - 1);
    };
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    for (size_t i : pieces) {
      const Piece& p = pieces_[i];
      centre += 0.5 * (p.a + p.b);
      const double h = o_.wall_height_m;
      const uint32_t a0 = vertex(p.a, 0), b0 = vertex(p.b, 0);
      const uint32_t a1 = vertex(p.a, h / 2), b1 = vertex(p.b, h / 2);
      const uint32_t a2 = vertex(p.a, h), b2 = vertex(p.b, h);
      for (uint32_t t : {a0, b0, b1, a0, b1, a1, a1, b1, b2, a1, b2, a2})
        mesh->triangles.push_back(t);
    }
    centre /= static_cast<double>(pieces.size());
    const uint32_t f0 = vertex(centre + Eigen::Vector2d(-0.5, -0.5), 0);
    const uint32_t f1 = vertex(centre + Eigen::Vector2d(0.5, -0.5), 0);
    const uint32_t f2 = vertex(centre + Eigen::Vector2d(0.5, 0.5), 0);
    const uint32_t f3 = vertex(centre + Eigen::Vector2d(-0.5, 0.5), 0);
    for (uint32_t t : {f0, f1, f2, f0, f2, f3}) mesh->triangles.push_back(t);
  }

  const std::vector<Piece>& pieces_;
  const DemoWalkOptions& o_;
  std::map<int64_t, std::set<size_t>> chunk_pieces_;  // pieces seen per chunk
  std::map<int64_t, double> chunk_emitted_s_;
  std::map<int64_t, uint64_t> chunk_ids_;
  std::set<int64_t> dirty_;
};

// The wall pick: the plan wall nearest the start, its normal facing the wearer; in the
// SLAM frame T0 with the options' point and normal errors.
WallPick NearestWallPick(const FloorPlan& plan, const Eigen::Vector2d& start, const Se2& T0,
                         const DemoWalkOptions& o, SplitMix64& rng) {
  WallPick pick;
  double best = 1e300;
  for (const Segment& s : plan.segments) {
    const Eigen::Vector2d c = ClosestPointOnSegment(s, start);
    if ((c - start).norm() < best) {
      best = (c - start).norm();
      pick.plan_point = c;
      pick.plan_normal = s.Normal();
      if (pick.plan_normal.dot(start - c) < 0) pick.plan_normal = -pick.plan_normal;
    }
  }
  const double normal_error = o.pick_normal_error_rad * rng.Gaussian();
  pick.slam_point =
      T0 * pick.plan_point + o.pick_point_error_m * Eigen::Vector2d(rng.Gaussian(), rng.Gaussian());
  pick.slam_normal = Se2{T0.theta + normal_error, {0, 0}}.R() * pick.plan_normal;
  return pick;
}

}  // namespace

DemoWalk SimulateDemoWalk(const FloorPlan& plan, const std::vector<Eigen::Vector2d>& waypoints,
                          const DemoWalkOptions& o) {
  DemoWalk walk;
  if (waypoints.size() < 2) return walk;
  SplitMix64 rng(o.seed);
  const std::vector<Piece> pieces = CutPieces(plan, o.piece_m);
  const std::vector<Pose2> truth = TruthAlong(waypoints, o.speed_mps * o.pose_period_s);
  // SLAM: integrate the true body-frame increments with a scale error and heading bias.
  Se2 T_slam_plan{o.initial_theta_rad, o.initial_offset_m};
  walk.T_slam_plan_initial = T_slam_plan;
  Pose2 slam = Apply(T_slam_plan, truth[0]);
  Mesher mesher(pieces, o);
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
    mesher.See(truth[k].position);
    if (k % o.poses_per_mesh_update == 0)
      mesher.Emit(k * o.pose_period_s, T_slam_plan, rng, &step.meshes);
    walk.steps.push_back(std::move(step));
  }
  walk.pick = NearestWallPick(plan, truth[0].position, walk.T_slam_plan_initial, o, rng);
  return walk;
}

}  // namespace floorpose::sim
