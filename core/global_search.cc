#include "core/global_search.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <queue>
#include <utility>

#include "core/closest_wall_index.h"

namespace floorpose {

struct GlobalSearch::Node {
  float bound;
  int rotation, h, x, y;
  bool operator<(const Node& o) const {  // the heap's top is the highest bound
    if (bound != o.bound) return bound < o.bound;
    if (h != o.h) return h > o.h;  // leaves first among equals: they end the search sooner
    if (rotation != o.rotation) return rotation > o.rotation;
    return x != o.x ? x > o.x : y > o.y;
  }
};

GlobalSearch::GlobalSearch(const FloorPlan& plan, GlobalSearchOptions options) : options_(options) {
  options_.depth = std::clamp(options_.depth, 1, 12);
  grid_ = GridGeometry::Cover(plan.min, plan.max, options_.cell_m, options_.margin_m,
                              options_.max_cells);
  const double sigma = std::max(options_.sigma_m, 0.5 * grid_.cell_m);
  ClosestWallIndex::Options index_options;
  index_options.max_distance_m = 4.0 * sigma;
  const ClosestWallIndex index(plan, index_options);

  pad_ = 1 << (options_.depth - 1);
  stride_ = grid_.nx + pad_;
  rows_ = grid_.ny + pad_;
  const size_t size = static_cast<size_t>(stride_) * static_cast<size_t>(rows_);
  pyramid_.assign(static_cast<size_t>(options_.depth), std::vector<float>(size, 0.0f));
  std::vector<float>& level0 = pyramid_[0];
  for (int iy = 0; iy < grid_.ny; ++iy)
    for (int ix = 0; ix < grid_.nx; ++ix) {
      const auto hit = index.Query(grid_.CellCentre(iy * grid_.nx + ix));
      if (!hit) continue;
      level0[static_cast<size_t>(iy + pad_) * stride_ + ix + pad_] =
          static_cast<float>(std::exp(-hit->distance * hit->distance / (2 * sigma * sigma)));
    }
  // Level h from h - 1: the best of the four half-size squares that tile it.
  for (int h = 1; h < options_.depth; ++h) {
    const int half = 1 << (h - 1);
    const std::vector<float>& below = pyramid_[static_cast<size_t>(h - 1)];
    std::vector<float>& level = pyramid_[static_cast<size_t>(h)];
    auto at = [&](int X, int Y) {
      return X < stride_ && Y < rows_ ? below[static_cast<size_t>(Y) * stride_ + X] : 0.0f;
    };
    for (int Y = 0; Y < rows_; ++Y)
      for (int X = 0; X < stride_; ++X)
        level[static_cast<size_t>(Y) * stride_ + X] =
            std::max({at(X, Y), at(X + half, Y), at(X, Y + half), at(X + half, Y + half)});
  }
}

size_t GlobalSearch::MemoryBytes() const {
  return pyramid_.size() * static_cast<size_t>(stride_) * static_cast<size_t>(rows_) *
         sizeof(float);
}

double GlobalSearch::Score(const std::vector<Eigen::Vector2d>& points_slam,
                           const Se2& T_plan_slam) const {
  double sum = 0;
  size_t n = 0;
  for (const Eigen::Vector2d& p : points_slam) {
    if (!p.allFinite()) continue;
    ++n;
    const int cell = grid_.CellOf(T_plan_slam * p);
    if (cell >= 0) sum += Bound(0, cell % grid_.nx, cell / grid_.nx);
  }
  return n ? sum / static_cast<double>(n) : 0.0;
}

std::vector<GlobalPlace> GlobalSearch::Search(const std::vector<Eigen::Vector2d>& points_slam,
                                              const std::vector<double>& rotations,
                                              GlobalSearchStats* stats) const {
  GlobalSearchStats local;
  GlobalSearchStats& st = stats ? *stats : local;
  st = {};
  const double cell = grid_.cell_m;

  // Thinned: one point a cell (the first), then a stride down to max_points.
  std::map<std::pair<int64_t, int64_t>, Eigen::Vector2d> voxels;
  for (const Eigen::Vector2d& p : points_slam) {
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() > 1e6) continue;
    voxels.emplace(std::make_pair(static_cast<int64_t>(std::floor(p.x() / cell)),
                                  static_cast<int64_t>(std::floor(p.y() / cell))),
                   p);
  }
  if (voxels.empty()) return {};
  const size_t step = std::max<size_t>(
      1, (voxels.size() + options_.max_points - 1) / std::max<size_t>(1, options_.max_points));
  std::vector<Eigen::Vector2d> cloud;
  size_t k = 0;
  for (const auto& [key, p] : voxels)
    if (k++ % step == 0) cloud.push_back(p);
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& p : cloud) centre += p;
  centre /= static_cast<double>(cloud.size());
  double reach = 0;
  for (const Eigen::Vector2d& p : cloud) reach = std::max(reach, (p - centre).norm());
  st.points = cloud.size();

  // Headings: every rotation_step (by default one cell of arc at the farthest point).
  std::vector<double> angles = rotations;
  if (angles.empty()) {
    double step_rad = options_.rotation_step_rad;
    if (!(step_rad > 0)) {
      const double d = std::max(reach, cell);
      step_rad = std::acos(std::clamp(1.0 - cell * cell / (2 * d * d), -1.0, 1.0));
    }
    step_rad = std::clamp(step_rad, 0.1 * M_PI / 180, 5.0 * M_PI / 180);
    const int n = static_cast<int>(std::ceil(2 * M_PI / step_rad));
    for (int i = 0; i < n; ++i) angles.push_back(WrapAngle(i * 2 * M_PI / n));
  }
  st.rotations = angles.size();

  // Per heading, each point's cell offset from the cell of the cloud's centre.
  const int n_points = static_cast<int>(cloud.size());
  std::vector<std::vector<Eigen::Vector2i>> offsets(angles.size());
  for (size_t r = 0; r < angles.size(); ++r) {
    const Se2 rotate{angles[r], Eigen::Vector2d::Zero()};
    for (const Eigen::Vector2d& p : cloud) {
      const Eigen::Vector2d q = rotate * (p - centre) / cell;
      offsets[r].emplace_back(static_cast<int>(std::floor(q.x() + 0.5)),
                              static_cast<int>(std::floor(q.y() + 0.5)));
    }
  }
  auto bound = [&](int r, int h, int x, int y) {
    float sum = 0;
    for (const Eigen::Vector2i& o : offsets[static_cast<size_t>(r)])
      sum += Bound(h, x + o.x(), y + o.y());
    ++st.nodes;
    return sum / static_cast<float>(n_points);
  };

  // Best first: a leaf off the top of the heap scores at least as well as every
  // translation not yet looked at, so places come out in the order of their scores.
  const float threshold = static_cast<float>(options_.min_score);
  std::priority_queue<Node> open;
  const int top = options_.depth - 1;
  for (int r = 0; r < static_cast<int>(angles.size()); ++r)
    for (int y = 0; y < grid_.ny; y += 1 << top)
      for (int x = 0; x < grid_.nx; x += 1 << top)
        if (const float b = bound(r, top, x, y); b >= threshold) open.push({b, r, top, x, y});

  std::vector<GlobalPlace> places;
  std::vector<std::pair<double, Eigen::Vector2d>> found;  // heading, centre cell (x, y)
  const double distinct_cells = options_.distinct_m / cell;
  // Every translation of the node within distinct_m of a place found at a near heading.
  auto covered = [&](const Node& n) {
    const double size = (1 << n.h) - 1;
    for (const auto& [angle, at] : found) {
      if (std::abs(WrapAngle(angles[static_cast<size_t>(n.rotation)] - angle)) >=
          options_.distinct_rad)
        continue;
      const double dx = std::max(std::abs(n.x - at.x()), std::abs(n.x + size - at.x()));
      const double dy = std::max(std::abs(n.y - at.y()), std::abs(n.y + size - at.y()));
      if (std::hypot(dx, dy) < distinct_cells) return true;
    }
    return false;
  };
  while (!open.empty() && places.size() < options_.places) {
    const Node n = open.top();
    open.pop();
    if (!places.empty() && n.bound < options_.min_ratio * places.front().score) break;
    if (covered(n)) continue;
    if (n.h == 0) {
      const double angle = angles[static_cast<size_t>(n.rotation)];
      const Se2 rotate{angle, Eigen::Vector2d::Zero()};
      const Eigen::Vector2d at = grid_.origin + cell * Eigen::Vector2d(n.x + 0.5, n.y + 0.5);
      places.push_back({Se2{angle, at - rotate * centre}, n.bound});
      found.emplace_back(angle, Eigen::Vector2d(n.x, n.y));
      continue;
    }
    const int half = 1 << (n.h - 1);
    for (int dy = 0; dy <= half; dy += half)
      for (int dx = 0; dx <= half; dx += half) {
        const int x = n.x + dx, y = n.y + dy;
        if (x >= grid_.nx || y >= grid_.ny) continue;
        if (const float b = bound(n.rotation, n.h - 1, x, y); b >= threshold)
          open.push({b, n.rotation, n.h - 1, x, y});
      }
  }
  return places;
}

}  // namespace floorpose
