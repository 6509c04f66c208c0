// Engine's crash safety (platform/engine.h): the state snapshot a restarted daemon resumes
// from, and every check a snapshot read back must pass before anything of it is kept.
#include "platform/engine.h"

namespace floorpose::platform {

v1::StateSnapshot Engine::SaveState() const {
  v1::StateSnapshot s;
  s.set_device_id(config().dds().device_id());
  s.set_plan_path(plans_.path());
  s.set_plan_digest(plans_.current().digest);
  s.set_floor(plans_.floor());
  s.set_latest_stamp_ns(intake_.clock().newest_ns());
  s.set_stamp_offset_ns(intake_.clock().offset_ns());
  const TrackerState t = tracker_.SaveState();
  *s.mutable_alignment() = ToProto(t.alignment, plans_.floor());
  s.set_next_version(t.next_version);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) s.add_covariance(t.P(r, c));
  s.set_pivot_x(t.pivot.x());
  s.set_pivot_y(t.pivot.y());
  s.set_has_pick(t.pick_plan_point.has_value());
  if (t.pick_plan_point) {
    s.set_pick_x(t.pick_plan_point->x());
    s.set_pick_y(t.pick_plan_point->y());
  }
  s.mutable_samples()->Reserve(static_cast<int>(4 * t.samples.size()));
  for (const tracking::Sample& sample : t.samples)
    for (double v : {sample.T_plan_slam.theta, sample.T_plan_slam.t.x(), sample.T_plan_slam.t.y(),
                     sample.log_weight})
      s.add_samples(v);
  s.set_elsewhere(t.elsewhere);
  s.set_checked(t.checked);
  store_.ForEachMesh([&](uint64_t id, const std::vector<WallPoint>& points, int64_t stamp_ns) {
    v1::StateSnapshot::Mesh* m = s.add_meshes();
    m->set_mesh_id(id);
    m->set_stamp_ns(stamp_ns);
    m->mutable_points()->Reserve(static_cast<int>(2 * points.size()));
    m->mutable_normals()->Reserve(static_cast<int>(2 * points.size()));
    for (const WallPoint& p : points) {
      m->add_points(p.p.x());
      m->add_points(p.p.y());
      m->add_normals(p.n.x());
      m->add_normals(p.n.y());
    }
  });
  return s;
}

namespace {

// Coordinates as the codec bounds the headset's (slam frame), twice that on the plan.
bool Within(const Eigen::Vector2d& v, double limit) {
  return v.allFinite() && v.cwiseAbs().maxCoeff() <= limit;
}

using SnapshotMeshes =
    std::vector<std::pair<const v1::StateSnapshot::Mesh*, std::vector<WallPoint>>>;

// The snapshot's wall store, checked whole before anything is kept; why not, if refused.
std::string ReadSnapshotMeshes(const v1::StateSnapshot& s, size_t max_wall_points, double max_abs,
                               SnapshotMeshes* meshes) {
  size_t total = 0;
  for (const v1::StateSnapshot::Mesh& m : s.meshes()) total += m.points_size() / 2;
  if (total > max_wall_points)
    return std::to_string(total) + " wall points, more than limits.max_wall_points";
  for (const v1::StateSnapshot::Mesh& m : s.meshes()) {
    if (m.points_size() % 2 != 0 || m.points_size() != m.normals_size())
      return "with mesh " + std::to_string(m.mesh_id()) + " malformed";
    std::vector<WallPoint> points(static_cast<size_t>(m.points_size() / 2));
    for (size_t i = 0; i < points.size(); ++i) {
      const int k = static_cast<int>(2 * i);
      points[i].p = {m.points(k), m.points(k + 1)};
      points[i].n = {m.normals(k), m.normals(k + 1)};
      if (!Within(points[i].p.cast<double>(), max_abs) || !Within(points[i].n.cast<double>(), 2))
        return "with mesh " + std::to_string(m.mesh_id()) + " not finite or out of range";
    }
    meshes->emplace_back(&m, std::move(points));
  }
  return {};
}

// The snapshot's alignment and belief, checked; why not, if refused.
std::string ReadTrackerState(const v1::StateSnapshot& s, double max_abs, TrackerState* t) {
  const v1::Alignment& a = s.alignment();
  t->alignment.T_plan_slam = {a.t_plan_slam().theta(), {a.t_plan_slam().x(), a.t_plan_slam().y()}};
  t->alignment.version = a.version();
  t->alignment.stamp_ns = a.stamp_ns();
  switch (a.source()) {
    case v1::Alignment::WALL_PICK: t->alignment.source = AlignmentSource::kWallPick; break;
    case v1::Alignment::FLIP: t->alignment.source = AlignmentSource::kFlip; break;
    case v1::Alignment::REGISTRATION: t->alignment.source = AlignmentSource::kRegistration; break;
    case v1::Alignment::GLOBAL_SEARCH: t->alignment.source = AlignmentSource::kGlobalSearch; break;
    default: return "with an alignment of unknown source";
  }
  t->next_version = s.next_version();
  if (s.covariance_size() != 9) return "without the belief's covariance";
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) t->P(r, c) = s.covariance(3 * r + c);
  t->pivot = {s.pivot_x(), s.pivot_y()};
  if (s.has_pick()) t->pick_plan_point = Eigen::Vector2d(s.pick_x(), s.pick_y());
  if (s.samples_size() % 4 != 0) return "with belief samples malformed";
  for (int i = 0; i + 3 < s.samples_size(); i += 4)
    t->samples.push_back({{s.samples(i), {s.samples(i + 1), s.samples(i + 2)}}, s.samples(i + 3)});
  t->elsewhere = s.elsewhere();
  t->checked = s.checked();
  if (!Within(t->alignment.T_plan_slam.t, 2 * max_abs) || !Within(t->pivot, 2 * max_abs) ||
      (t->pick_plan_point && !Within(*t->pick_plan_point, 2 * max_abs)) ||
      !(t->P.cwiseAbs().maxCoeff() <= 1e6) || !(t->elsewhere >= 0 && t->elsewhere <= 1))
    return "with an alignment or its belief out of range";
  return {};
}

}  // namespace

std::string Engine::RestoreState(const v1::StateSnapshot& s) {
  if (s.device_id() != config().dds().device_id())
    return "of device '" + s.device_id() + "', not '" + config().dds().device_id() + "'";
  if (s.plan_path().empty()) return "without a floor plan";
  // The app may have loaded another plan before the restart: that one again, and back to
  // the configured one if the snapshot is refused after all.
  const std::string configured_plan = plans_.path(), configured_floor = plans_.floor();
  bool switched = false;
  auto refuse = [&](const std::string& why) {
    if (switched) {
      if (configured_plan.empty()) {
        tracker_.SetPlan(nullptr);
        plans_.Clear();
      } else {
        LoadPlan(configured_plan, configured_floor);
      }
    }
    return why;
  };
  if (s.plan_path() != plans_.path() || s.floor() != plans_.floor()) {
    if (const std::string e = LoadPlan(s.plan_path(), s.floor()); !e.empty())
      return refuse("of plan " + s.plan_path() + ", which does not load now: " + e);
    switched = true;
  }
  if (s.plan_digest() != plans_.current().digest)
    return refuse("of plan " + s.plan_path() + " as it was before it changed");
  // The wall store first, checked whole before anything is kept.
  const double max_abs = config().limits().max_abs_coordinate_m();
  SnapshotMeshes meshes;
  if (const std::string e =
          ReadSnapshotMeshes(s, config().limits().max_wall_points(), max_abs, &meshes);
      !e.empty())
    return refuse(e);
  if (s.alignment().version() > 0) {
    TrackerState t;
    if (const std::string e = ReadTrackerState(s, max_abs, &t); !e.empty()) return refuse(e);
    if (const std::string e = tracker_.RestoreState(t); !e.empty()) return refuse("with " + e);
  }
  store_.Clear();
  for (auto& [m, points] : meshes) store_.Upsert(m->mesh_id(), std::move(points), m->stamp_ns());
  store_.TakeNewPoints();
  intake_.clock().Restore(std::max(intake_.clock().newest_ns(), s.latest_stamp_ns()),
                          s.stamp_offset_ns(), now_ns_());
  return {};
}

}  // namespace floorpose::platform
