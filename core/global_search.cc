#include "core/global_search.h"

#include <algorithm>
#include <cmath>
#include <limits>
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
  plan_directions_.assign(180, 0.0);
  for (const Segment& seg : plan.segments) {
    const Eigen::Vector2d d = seg.b - seg.a;
    const double deg = std::fmod(std::atan2(d.y(), d.x()) * 180 / M_PI + 360.0, 180.0);
    plan_directions_[static_cast<size_t>(deg) % 180] += seg.Length();
  }
  grid_ = GridGeometry::Cover(plan.min, plan.max, options_.cell_m, options_.margin_m,
                              options_.max_cells);
  const double sigma = std::max(options_.sigma_m, 0.5 * grid_.cell_m);
  ClosestWallIndex::Options index_options;
  index_options.max_distance_m = 4.0 * sigma;
  index_options.grid_cell_m = 0;  // asked once a cell
  const ClosestWallIndex index(plan, index_options);

  pad_ = 1 << (options_.depth - 1);
  stride_ = grid_.nx + pad_;
  rows_ = grid_.ny + pad_;
  const size_t size = static_cast<size_t>(stride_) * static_cast<size_t>(rows_);
  likelihood_.assign(size, 0.0f);
  for (int iy = 0; iy < grid_.ny; ++iy)
    for (int ix = 0; ix < grid_.nx; ++ix) {
      const auto hit = index.Query(grid_.CellCentre(iy * grid_.nx + ix));
      if (!hit) continue;
      likelihood_[static_cast<size_t>(iy + pad_) * stride_ + ix + pad_] =
          static_cast<float>(std::exp(-hit->distance * hit->distance / (2 * sigma * sigma)));
    }
  // Level h from h - 1: the best of the four half-size squares that tile it. Level 1 is
  // rounded up to steps (a float times kSteps is exact in double), so it bounds level 0.
  bounds_.assign(static_cast<size_t>(options_.depth - 1), std::vector<uint8_t>(size, 0));
  for (int h = 1; h < options_.depth; ++h) {
    const int half = 1 << (h - 1);
    std::vector<uint8_t>& level = bounds_[static_cast<size_t>(h - 1)];
    auto at = [&](int X, int Y) -> double {
      if (X >= stride_ || Y >= rows_) return 0.0;
      const size_t i = static_cast<size_t>(Y) * stride_ + X;
      return h == 1 ? kSteps * static_cast<double>(likelihood_[i])
                    : bounds_[static_cast<size_t>(h - 2)][i];
    };
    for (int Y = 0; Y < rows_; ++Y)
      for (int X = 0; X < stride_; ++X)
        level[static_cast<size_t>(Y) * stride_ + X] = static_cast<uint8_t>(
            std::min<double>(kSteps, std::ceil(std::max({at(X, Y), at(X + half, Y), at(X, Y + half),
                                                         at(X + half, Y + half)}))));
  }
}

size_t GlobalSearch::MemoryBytes() const {
  return likelihood_.size() * sizeof(float) + bounds_.size() * likelihood_.size();
}

double GlobalSearch::HeadingStep(double reach_m) const {
  const double cell = grid_.cell_m;
  double step = options_.rotation_step_rad;
  if (!(step > 0)) {
    const double d = std::max(reach_m, cell);
    step = std::acos(std::clamp(1.0 - cell * cell / (2 * d * d), -1.0, 1.0));
  }
  return std::clamp(step, 0.1 * M_PI / 180, 5.0 * M_PI / 180);
}

namespace {

// The mean of a cloud's points, and how far the farthest of them lies from it.
struct Extent {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double reach = 0;
};

Extent ExtentOf(const std::vector<Eigen::Vector2d>& points) {
  Extent e;
  for (const Eigen::Vector2d& p : points) e.centre += p;
  e.centre /= static_cast<double>(points.size());
  for (const Eigen::Vector2d& p : points) e.reach = std::max(e.reach, (p - e.centre).norm());
  return e;
}

// Points binned in cells of kDirectionRadiusM: each cell's neighbourhood is a local line fit.
constexpr double kDirectionRadiusM = 0.3;
using DirectionBins = std::map<std::pair<int64_t, int64_t>, std::vector<Eigen::Vector2d>>;

// The cloud's wall directions, a histogram by degree modulo 180: a line fit through each
// point's neighbours within 0.3 m (its cell and the eight around), counted when the
// neighbours lie along a line. `bins` holds the finite points by cell.
std::vector<double> CloudDirections(const std::vector<Eigen::Vector2d>& points_slam,
                                    DirectionBins* bins) {
  for (const Eigen::Vector2d& p : points_slam)
    if (p.allFinite() && p.cwiseAbs().maxCoeff() < 1e6)
      (*bins)[{static_cast<int64_t>(std::floor(p.x() / kDirectionRadiusM)),
               static_cast<int64_t>(std::floor(p.y() / kDirectionRadiusM))}]
          .push_back(p);
  std::vector<double> cloud(180, 0.0);
  for (const auto& [key, members] : *bins) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    int n = 0;
    for (int64_t dy = -1; dy <= 1; ++dy)
      for (int64_t dx = -1; dx <= 1; ++dx) {
        const auto it = bins->find({key.first + dx, key.second + dy});
        if (it == bins->end()) continue;
        for (const Eigen::Vector2d& q : it->second) {
          mean += q;
          scatter += q * q.transpose();
          ++n;
        }
      }
    if (n < 5) continue;
    mean /= n;
    const Eigen::Matrix2d cov = scatter / n - mean * mean.transpose();
    // Direction of the larger eigenvalue, and how line-like (1: a line, 0: a blob).
    const double tr = cov.trace(), det = cov(0, 0) * cov(1, 1) - cov(0, 1) * cov(1, 0);
    const double gap = std::sqrt(std::max(0.0, tr * tr / 4 - det));
    const double large = tr / 2 + gap, small = tr / 2 - gap;
    if (!(large > 1e-6)) continue;
    const double angle = 0.5 * std::atan2(2 * cov(0, 1), cov(0, 0) - cov(1, 1));
    const double deg = std::fmod(angle * 180 / M_PI + 360.0, 180.0);
    cloud[static_cast<size_t>(deg) % 180] +=
        static_cast<double>(members.size()) * std::max(0.0, 1.0 - small / large * 10);
  }
  return cloud;
}

// The shifts, in degrees, at which the two direction histograms line up best: the circular
// correlation of the two (each lightly smoothed), its best `max_peaks` local maxima at
// least 5 degrees apart. None when nothing correlates.
std::vector<int> DirectionPeaks(const std::vector<double>& cloud, const std::vector<double>& plan,
                                int max_peaks) {
  auto smooth = [](const std::vector<double>& h) {
    std::vector<double> out(180, 0.0);
    for (int i = 0; i < 180; ++i)
      out[i] = 0.25 * h[(i + 179) % 180] + 0.5 * h[i] + 0.25 * h[(i + 1) % 180];
    return out;
  };
  const std::vector<double> a = smooth(cloud), b = smooth(plan);
  std::vector<double> correlation(180, 0.0);
  for (int shift = 0; shift < 180; ++shift)
    for (int i = 0; i < 180; ++i) correlation[shift] += a[i] * b[(i + shift) % 180];
  if (*std::max_element(correlation.begin(), correlation.end()) <= 0) return {};
  std::vector<int> peaks;
  for (int i = 0; i < 180; ++i)
    if (correlation[i] > 0 && correlation[i] >= correlation[(i + 179) % 180] &&
        correlation[i] >= correlation[(i + 1) % 180])
      peaks.push_back(i);
  std::sort(peaks.begin(), peaks.end(),
            [&](int x, int y) { return correlation[x] > correlation[y]; });
  std::vector<int> chosen;
  for (int p : peaks) {
    if (static_cast<int>(chosen.size()) >= max_peaks) break;
    bool near = false;
    for (int c : chosen) near = near || std::min(std::abs(p - c), 180 - std::abs(p - c)) < 5;
    if (!near) chosen.push_back(p);
  }
  return chosen;
}

}  // namespace

std::vector<double> GlobalSearch::WallHeadings(
    const std::vector<Eigen::Vector2d>& points_slam) const {
  DirectionBins bins;
  const std::vector<double> cloud = CloudDirections(points_slam, &bins);
  const std::vector<int> chosen = DirectionPeaks(cloud, plan_directions_, options_.heading_peaks);
  if (chosen.empty()) return {};
  // Each alignment and its half turn, widened by the spread in Search's heading steps.
  std::vector<Eigen::Vector2d> finite;
  for (const auto& [key, members] : bins)
    finite.insert(finite.end(), members.begin(), members.end());
  std::vector<double> headings;
  const double step = HeadingStep(ExtentOf(finite).reach);
  const int n = static_cast<int>(std::ceil(options_.heading_spread_rad / step));
  for (int c : chosen)
    for (double half : {0.0, M_PI})
      for (int k = -n; k <= n; ++k) headings.push_back(WrapAngle(c * M_PI / 180 + half + k * step));
  return headings;
}

double GlobalSearch::Score(const std::vector<Eigen::Vector2d>& points_slam,
                           const Se2& T_plan_slam) const {
  double sum = 0;
  size_t n = 0;
  for (const Eigen::Vector2d& p : points_slam) {
    if (!p.allFinite()) continue;
    ++n;
    const int cell = grid_.CellOf(T_plan_slam * p);
    if (cell >= 0) sum += Likelihood(cell % grid_.nx, cell / grid_.nx);
  }
  return n ? sum / static_cast<double>(n) : 0.0;
}

// A cloud turned to one heading: each point's cell offset from the cell of the cloud's
// centre, the same as an offset into the pyramid's arrays (rows of `stride_`), and their
// bounds. A node whose points all land on the arrays is summed without a bound check per
// point (on a laser log few do: its cloud reaches past the plan's edge from most cells).
struct GlobalSearch::Offsets {
  std::vector<Eigen::Vector2i> cell;
  std::vector<ptrdiff_t> linear;
  Eigen::Vector2i min{0, 0}, max{0, 0};
};

namespace {

// One point a cell (the first, in cell order), then a stride down to max_points; points
// not finite or beyond 1000 km left out.
std::vector<Eigen::Vector2d> ThinToCells(const std::vector<Eigen::Vector2d>& points, double cell,
                                         size_t max_points) {
  std::map<std::pair<int64_t, int64_t>, Eigen::Vector2d> voxels;
  for (const Eigen::Vector2d& p : points) {
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() > 1e6) continue;
    voxels.emplace(std::make_pair(static_cast<int64_t>(std::floor(p.x() / cell)),
                                  static_cast<int64_t>(std::floor(p.y() / cell))),
                   p);
  }
  if (voxels.empty()) return {};
  const size_t step =
      std::max<size_t>(1, (voxels.size() + max_points - 1) / std::max<size_t>(1, max_points));
  std::vector<Eigen::Vector2d> cloud;
  size_t k = 0;
  for (const auto& [key, p] : voxels)
    if (k++ % step == 0) cloud.push_back(p);
  return cloud;
}

// The least float at or above v: a float compares with it as with v.
float FloatAtLeast(double v) {
  const auto f = static_cast<float>(v);
  return static_cast<double>(f) < v ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

// Whether every translation of a node (heading `angle`, level h, at cell x, y) lies within
// distinct_cells of a place found at a heading within distinct_rad.
bool Covered(const std::vector<std::pair<double, Eigen::Vector2d>>& found, double angle, int h,
             int x, int y, double distinct_cells, double distinct_rad) {
  const double size = (1 << h) - 1;
  for (const auto& [found_angle, at] : found) {
    if (std::abs(WrapAngle(angle - found_angle)) >= distinct_rad) continue;
    const double dx = std::max(std::abs(x - at.x()), std::abs(x + size - at.x()));
    const double dy = std::max(std::abs(y - at.y()), std::abs(y + size - at.y()));
    if (std::hypot(dx, dy) < distinct_cells) return true;
  }
  return false;
}

}  // namespace

std::vector<GlobalPlace> GlobalSearch::Search(const std::vector<Eigen::Vector2d>& points_slam,
                                              const std::vector<double>& rotations,
                                              GlobalSearchStats* stats) const {
  GlobalSearchStats local;
  GlobalSearchStats& st = stats ? *stats : local;
  st = {};
  const double cell = grid_.cell_m;

  const std::vector<Eigen::Vector2d> cloud = ThinToCells(points_slam, cell, options_.max_points);
  if (cloud.empty()) return {};
  const Extent extent = ExtentOf(cloud);
  st.points = cloud.size();

  // Headings: every rotation_step (by default one cell of arc at the farthest point).
  std::vector<double> angles = rotations;
  if (angles.empty()) {
    const double step_rad = HeadingStep(extent.reach);
    const int n = static_cast<int>(std::ceil(2 * M_PI / step_rad));
    for (int i = 0; i < n; ++i) angles.push_back(WrapAngle(i * 2 * M_PI / n));
  }
  st.rotations = angles.size();
  return BestFirst(HeadingOffsets(cloud, extent.centre, angles), angles, extent.centre, st);
}

std::vector<GlobalSearch::Offsets> GlobalSearch::HeadingOffsets(
    const std::vector<Eigen::Vector2d>& cloud, const Eigen::Vector2d& centre,
    const std::vector<double>& angles) const {
  std::vector<Offsets> offsets(angles.size());
  for (size_t r = 0; r < angles.size(); ++r) {
    const Se2 rotate{angles[r], Eigen::Vector2d::Zero()};
    Offsets& o = offsets[r];
    for (const Eigen::Vector2d& p : cloud) {
      const Eigen::Vector2d q = rotate * (p - centre) / grid_.cell_m;
      const Eigen::Vector2i c(static_cast<int>(std::floor(q.x() + 0.5)),
                              static_cast<int>(std::floor(q.y() + 0.5)));
      o.min = o.cell.empty() ? c : o.min.cwiseMin(c);
      o.max = o.cell.empty() ? c : o.max.cwiseMax(c);
      o.cell.push_back(c);
      o.linear.push_back(static_cast<ptrdiff_t>(c.y()) * stride_ + c.x());
    }
  }
  return offsets;
}

float GlobalSearch::Bound(const Offsets& o, int h, int x, int y, float need) const {
  // Summed a block of points at a time: once the points left, each worth at most `top`,
  // cannot lift the sum to `floor` (need, less a float rounding's worth), the node is
  // pruned whatever they add, and the sum so far is returned below need.
  constexpr size_t kBlock = 32;
  const size_t n = o.cell.size();
  const auto sum = [&](const auto* level, auto total, double top, double floor) {
    const auto* at = level + static_cast<ptrdiff_t>(y + pad_) * stride_ + (x + pad_);
    // The offsets that land on the arrays: [-pad_, nx) x [-pad_, ny) about the node.
    const Eigen::Vector2i lo(-pad_ - x, -pad_ - y), hi(grid_.nx - x, grid_.ny - y);
    const bool inside =
        o.min.x() >= lo.x() && o.max.x() < hi.x() && o.min.y() >= lo.y() && o.max.y() < hi.y();
    for (size_t begin = 0; begin < n; begin += kBlock) {
      const size_t end = std::min(n, begin + kBlock);
      if (inside) {
        for (size_t i = begin; i < end; ++i) total += at[o.linear[i]];
      } else {
        for (size_t i = begin; i < end; ++i) {
          const Eigen::Vector2i& c = o.cell[i];
          if (c.x() >= lo.x() && c.x() < hi.x() && c.y() >= lo.y() && c.y() < hi.y())
            total += at[o.linear[i]];
        }
      }
      if (static_cast<double>(total) + top * static_cast<double>(n - end) < floor) return total;
    }
    return total;
  };
  const auto n_points = static_cast<float>(n);
  const double need_sum = static_cast<double>(need) * static_cast<double>(n);
  if (h == 0) return sum(likelihood_.data(), 0.0f, 1.0, need_sum - 0.02) / n_points;
  const uint32_t steps =
      sum(bounds_[static_cast<size_t>(h - 1)].data(), uint32_t{0}, kSteps, need_sum * kSteps - 1);
  return static_cast<float>(steps) / (static_cast<float>(kSteps) * n_points);
}

std::vector<GlobalPlace> GlobalSearch::BestFirst(const std::vector<Offsets>& offsets,
                                                 const std::vector<double>& angles,
                                                 const Eigen::Vector2d& centre,
                                                 GlobalSearchStats& st) const {
  // Best first: a leaf off the top of the heap scores at least as well as every
  // translation not yet looked at, so places come out in the order of their scores.
  // A node below `need` is never pushed: min_score, and once places are found the share of
  // the best below which the loop below ends anyway.
  float need = static_cast<float>(options_.min_score);
  std::priority_queue<Node> open;
  const auto visit = [&](int r, int h, int x, int y) {
    ++st.nodes;
    if (const float b = Bound(offsets[static_cast<size_t>(r)], h, x, y, need); b >= need)
      open.push({b, r, h, x, y});
  };
  const int top = options_.depth - 1;
  for (int r = 0; r < static_cast<int>(angles.size()); ++r)
    for (int y = 0; y < grid_.ny; y += 1 << top)
      for (int x = 0; x < grid_.nx; x += 1 << top) visit(r, top, x, y);

  const double cell = grid_.cell_m;
  std::vector<GlobalPlace> places;
  std::vector<std::pair<double, Eigen::Vector2d>> found;  // heading, centre cell (x, y)
  const double distinct_cells = options_.distinct_m / cell;
  while (!open.empty() && places.size() < max_places()) {
    const Node n = open.top();
    open.pop();
    if (!places.empty() && n.bound < options_.min_ratio * places.front().score) break;
    if (places.size() >= options_.places && n.bound < options_.crowd_ratio * places.front().score)
      break;
    const double angle = angles[static_cast<size_t>(n.rotation)];
    if (Covered(found, angle, n.h, n.x, n.y, distinct_cells, options_.distinct_rad)) continue;
    if (n.h == 0) {
      const Se2 rotate{angle, Eigen::Vector2d::Zero()};
      const Eigen::Vector2d at = grid_.origin + cell * Eigen::Vector2d(n.x + 0.5, n.y + 0.5);
      places.push_back({Se2{angle, at - rotate * centre}, n.bound});
      found.emplace_back(angle, Eigen::Vector2d(n.x, n.y));
      const double ratio = places.size() >= options_.places
                               ? std::max(options_.min_ratio, options_.crowd_ratio)
                               : options_.min_ratio;
      need = std::max(need, FloatAtLeast(ratio * places.front().score));
      continue;
    }
    const int half = 1 << (n.h - 1);
    for (int dy = 0; dy <= half; dy += half)
      for (int dx = 0; dx <= half; dx += half)
        if (n.x + dx < grid_.nx && n.y + dy < grid_.ny)
          visit(n.rotation, n.h - 1, n.x + dx, n.y + dy);
  }
  return places;
}

namespace {

// One place refined on the walls: ICP from it, then its fit, the plan walls its walk goes
// through and, where asked, the walls it leaves hidden from the walk and the plan walls in
// sight the mesh lacks, each added to the fit as a miss. cloud_plan is scratch.
GlobalPlace RefinePlace(const GlobalPlace& place, const std::vector<Eigen::Vector2d>& cloud,
                        const std::vector<Eigen::Vector2d>& path_slam,
                        const ClosestWallIndex& index, const IcpOptions& icp,
                        const RefineOptions& options, std::vector<Eigen::Vector2d>& cloud_plan) {
  GlobalPlace r = place;
  const RegistrationResult icp_result = RegisterIcp(cloud, index, place.T_plan_slam, icp);
  if (icp_result.converged && icp_result.T_plan_slam.t.allFinite() &&
      std::isfinite(icp_result.T_plan_slam.theta))
    r.T_plan_slam = icp_result.T_plan_slam;
  RegistrationResult fit;
  EvaluateFit(cloud, index, r.T_plan_slam, options.cap_m, icp.inlier_threshold_m, &fit, &r.fit_mse);
  r.inlier_ratio = static_cast<double>(fit.inliers) / static_cast<double>(cloud.size());
  const std::vector<Eigen::Vector2d> path_plan = PathOnPlan(r.T_plan_slam, path_slam);
  r.path_crossings = PathCrossings(path_plan, index.plan(), options.path_margin_m);
  if (options.sight_reach_m > 0 || options.unseen_reach_m > 0) {
    cloud_plan.clear();
    for (const Eigen::Vector2d& p : cloud) cloud_plan.push_back(r.T_plan_slam * p);
  }
  if (options.sight_reach_m > 0) {
    // The walls seen must have been in sight: one the plan hides from the whole walk
    // is a miss, however well it lies on a wall (a look-alike room behind a wall).
    const uint32_t hidden = HiddenPoints(cloud_plan, path_plan, index.plan(), options.sight_reach_m,
                                         options.sight_standoff_m, options.path_margin_m);
    r.hidden_ratio = static_cast<double>(hidden) / static_cast<double>(cloud.size());
    r.fit_mse +=
        std::max(0.0, r.hidden_ratio - options.sight_allowance) * options.cap_m * options.cap_m;
  }
  if (options.unseen_reach_m > 0) {
    UnseenWallsOptions unseen;
    unseen.walls.reach_m = options.unseen_reach_m;
    unseen.walls.standoff_m = options.sight_standoff_m;
    unseen.walls.end_margin_m = options.path_margin_m;
    const UnseenWalls u = CountUnseenWalls(cloud_plan, path_plan, index.plan(), unseen);
    r.unseen_expected = u.expected;
    r.unseen_ratio = u.expected ? static_cast<double>(u.missed) / u.expected : 0.0;
    // Few samples tell little: the excess counts over at least unseen_min_samples.
    const double excess = std::max(0.0, u.missed - options.unseen_allowance * u.expected) /
                          std::max<double>(u.expected, options.unseen_min_samples);
    r.fit_mse += options.unseen_weight * excess * options.cap_m * options.cap_m;
  }
  return r;
}

// The places no better one stands within distinct_m and distinct_rad of (at the cloud's
// centre), best fit first.
std::vector<GlobalPlace> DistinctPlaces(std::vector<GlobalPlace> refined,
                                        const Eigen::Vector2d& centre,
                                        const RefineOptions& options) {
  std::stable_sort(refined.begin(), refined.end(), [](const GlobalPlace& a, const GlobalPlace& b) {
    return a.fit_mse < b.fit_mse;
  });
  std::vector<GlobalPlace> distinct;
  for (const GlobalPlace& r : refined) {
    const bool same = std::any_of(distinct.begin(), distinct.end(), [&](const GlobalPlace& d) {
      return (r.T_plan_slam * centre - d.T_plan_slam * centre).norm() < options.distinct_m &&
             std::abs(WrapAngle(r.T_plan_slam.theta - d.T_plan_slam.theta)) < options.distinct_rad;
    });
    if (!same) distinct.push_back(r);
  }
  return distinct;
}

void RankPlaces(std::vector<GlobalPlace>& distinct, const std::vector<Eigen::Vector2d>& path_slam,
                const ClosestWallIndex& index, const RefineOptions& options) {
  // A place that leaves most of the walls off the plan is no place, however it walks.
  // Among those that fit, a place is only as good as the walk it implies: those that take
  // the wearer through more walls than the fewest go last, so they can be the next place
  // but not the best. (A wrong place often walks the wearer outside the building, through
  // nothing; fitting comes first so that it cannot win on that.)
  const auto fits = [&](const GlobalPlace& d) {
    const bool blind = options.unseen_reach_m > 0 &&
                       d.unseen_expected >= options.unseen_min_samples &&
                       d.unseen_ratio > options.unseen_max_ratio;
    return d.inlier_ratio >= options.min_inliers && !blind;
  };
  uint32_t fewest = UINT32_MAX;
  for (const GlobalPlace& d : distinct)
    if (fits(d)) fewest = std::min(fewest, d.path_crossings);
  for (GlobalPlace& d : distinct) {
    d.rank = !fits(d) ? 2 : d.path_crossings > fewest ? 1 : 0;
    d.alike = -1;  // against this call's best, below
  }
  std::stable_sort(distinct.begin(), distinct.end(),
                   [](const GlobalPlace& a, const GlobalPlace& b) { return a.rank < b.rank; });
  if (options.alike_reach_m > 0 && !distinct.empty() && distinct.front().rank == 0)
    for (size_t i = 1; i < distinct.size() && distinct[i].rank == 0; ++i)
      distinct[i].alike =
          PlanAlike(path_slam, distinct.front().T_plan_slam, distinct[i].T_plan_slam, index,
                    options.alike_reach_m, 0.3, options.path_margin_m)
              .share;
}

}  // namespace

std::vector<GlobalPlace> RefinePlaces(const std::vector<GlobalPlace>& places,
                                      const std::vector<Eigen::Vector2d>& points_slam,
                                      const std::vector<Eigen::Vector2d>& path_slam,
                                      const ClosestWallIndex& index, const IcpOptions& icp,
                                      const RefineOptions& options,
                                      const std::vector<GlobalPlace>& ranked) {
  std::vector<Eigen::Vector2d> cloud;
  cloud.reserve(points_slam.size());
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& p : points_slam)
    if (p.allFinite()) cloud.push_back(p), centre += p;
  if (cloud.empty()) return {};
  centre /= static_cast<double>(cloud.size());
  std::vector<GlobalPlace> refined = ranked;  // refined on these walls already
  std::vector<Eigen::Vector2d> cloud_plan;
  for (const GlobalPlace& place : places)
    refined.push_back(RefinePlace(place, cloud, path_slam, index, icp, options, cloud_plan));
  std::vector<GlobalPlace> distinct = DistinctPlaces(std::move(refined), centre, options);
  RankPlaces(distinct, path_slam, index, options);
  return distinct;
}

std::vector<GlobalPlace> HalfTurnTwins(const GlobalSearch& search, const FloorPlan& plan,
                                       const Se2& place,
                                       const std::vector<Eigen::Vector2d>& path_slam,
                                       const std::vector<double>& headings,
                                       const WallSampleOptions& in_sight,
                                       GlobalSearchStats* stats) {
  std::vector<Eigen::Vector2d> walls =
      WallSamplesInSight(PathOnPlan(place, path_slam), plan, in_sight);
  if (walls.empty()) return {};
  const Se2 to_slam = place.Inverse();
  for (Eigen::Vector2d& q : walls) q = to_slam * q;
  const double turned = place.theta + M_PI;
  std::vector<double> twin_headings;
  for (double h : headings)
    if (std::abs(WrapAngle(h - turned)) <= search.options().distinct_rad)
      twin_headings.push_back(h);
  if (twin_headings.empty()) twin_headings.push_back(WrapAngle(turned));
  return search.Search(walls, twin_headings, stats);
}

PlanAlikeness PlanAlike(const std::vector<Eigen::Vector2d>& path_slam, const Se2& a, const Se2& b,
                        const ClosestWallIndex& index, double reach_m, double match_m,
                        double end_margin_m) {
  WallSampleOptions walls;
  walls.reach_m = reach_m;
  walls.end_margin_m = end_margin_m;
  // The share of `from`'s walls in sight that lie on the plan's walls again under `to`.
  const auto share = [&](const Se2& from, const Se2& to, uint32_t* samples) {
    const std::vector<Eigen::Vector2d> seen =
        WallSamplesInSight(PathOnPlan(from, path_slam), index.plan(), walls);
    const Se2 move = to * from.Inverse();
    uint32_t on_wall = 0;
    for (const Eigen::Vector2d& q : seen) {
      const std::optional<ClosestWall> c = index.Query(move * q);
      on_wall += c && c->distance <= match_m;
    }
    *samples = static_cast<uint32_t>(seen.size());
    return seen.empty() ? 0.0 : static_cast<double>(on_wall) / static_cast<double>(seen.size());
  };
  uint32_t n_ab = 0, n_ba = 0;
  const double ab = share(a, b, &n_ab);
  const double ba = share(b, a, &n_ba);
  return {std::min(ab, ba), std::min(n_ab, n_ba)};
}

}  // namespace floorpose
