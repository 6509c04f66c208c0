#include "core/closest_wall_index.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace floorpose {
namespace {

ClosestWall MakeHit(const FloorPlan& plan, uint32_t i, const Eigen::Vector2d& p) {
  const Segment& s = plan.segments[i];
  ClosestWall hit;
  hit.segment = i;
  hit.point = ClosestPointOnSegment(s, p);
  hit.normal = s.Normal();
  hit.distance = (hit.point - p).norm();
  return hit;
}

// At most this many cells (and the distance grid's): see SizeCells.
constexpr double kMaxCells = 1 << 24;

}  // namespace

ClosestWallIndex::ClosestWallIndex(const FloorPlan& plan, Options options)
    : plan_(plan), options_(options) {
  data_.reserve(plan_.segments.size());
  for (const Segment& s : plan_.segments) {
    const Eigen::Vector2d d = s.b - s.a;
    data_.push_back({s.a, d, s.Normal(), d.squaredNorm() > 0 ? 1.0 / d.squaredNorm() : 0.0});
  }
  SizeCells();
  std::vector<uint32_t> begin, lists;
  FillCandidates(&begin, &lists);
  SortCandidates(begin, &lists);
  PackCells(begin, lists);
  if (options_.grid_cell_m > 0)
    grid_ = DistanceGrid(plan_.segments, plan_.min, plan_.max, options_.grid_cell_m,
                         std::min(kGridNearM, options_.max_distance_m), kMaxCells);
}

void ClosestWallIndex::SizeCells() {
  // Memory is bounded by design: a plan too large for the requested cells (drawn in
  // millimetres, or with a stray far-away segment) gets coarser cells instead of
  // gigabytes or an overflowing cell count. Any cell size gives exact answers (see the
  // header); only the candidate lists grow.
  const Eigen::Vector2d size = plan_.max - plan_.min;
  auto cell_count = [&](double c) {
    const double margin2 = 2 * (options_.max_distance_m + c);
    return std::ceil((size.x() + margin2) / c) * std::ceil((size.y() + margin2) / c);
  };
  for (int i = 0; i < 2100 && !(cell_count(options_.cell_m) <= kMaxCells); ++i)
    options_.cell_m *= 2;
  const double cell = options_.cell_m;
  const double margin = options_.max_distance_m + cell;
  origin_ = plan_.min - Eigen::Vector2d::Constant(margin);
  const Eigen::Vector2d extent = size + Eigen::Vector2d::Constant(2 * margin);
  per_cell_ = 1.0 / cell;
  // std::max(1.0, NaN) is 1.0: no undefined conversion even for absurd bounds.
  nx_ = static_cast<int>(std::min(kMaxCells, std::max(1.0, std::ceil(extent.x() / cell))));
  ny_ = static_cast<int>(std::min(kMaxCells, std::max(1.0, std::ceil(extent.y() / cell))));
}

void ClosestWallIndex::FillCandidates(std::vector<uint32_t>* begin,
                                      std::vector<uint32_t>* lists) const {
  const double cell = options_.cell_m;
  const size_t n = static_cast<size_t>(nx_) * static_cast<size_t>(ny_);
  const double r = 0.5 * cell * std::sqrt(2.0);
  // Only segments within this distance of a centre can matter (see the header).
  const double reach = options_.max_distance_m + 2 * r;
  // Visits the cells whose centres may lie within `reach` of segment k, with the
  // segment's distance from each centre, but skips the cells whose centre is farther than
  // `beyond(i)` from the segment's bounding box (no nearer the segment itself), without
  // computing the distance: a raster plan's short segments are each within reach of
  // thousands of centres, nearly all of them nearer another segment.
  auto for_cells_near = [&](uint32_t k, auto&& beyond, auto&& fn) {
    const Segment& s = plan_.segments[k];
    const Eigen::Vector2d box_lo = s.a.cwiseMin(s.b), box_hi = s.a.cwiseMax(s.b);
    const Eigen::Vector2d lo = box_lo - Eigen::Vector2d::Constant(reach);
    const Eigen::Vector2d hi = box_hi + Eigen::Vector2d::Constant(reach);
    const int x0 = std::max(0, static_cast<int>(std::floor((lo.x() - origin_.x()) / cell)));
    const int y0 = std::max(0, static_cast<int>(std::floor((lo.y() - origin_.y()) / cell)));
    const int x1 = std::min(nx_ - 1, static_cast<int>(std::floor((hi.x() - origin_.x()) / cell)));
    const int y1 = std::min(ny_ - 1, static_cast<int>(std::floor((hi.y() - origin_.y()) / cell)));
    for (int iy = y0; iy <= y1; ++iy) {
      for (int ix = x0; ix <= x1; ++ix) {
        const size_t i = static_cast<size_t>(iy) * nx_ + ix;
        const Eigen::Vector2d c = CellCentre(ix, iy);
        const double far = beyond(i) + 1e-9;  // the slack covers the box distance's rounding
        if (SquaredDistanceToBox(c, box_lo, box_hi) > far * far) continue;
        fn(i, std::sqrt(data_[k].Distance2(c)));
      }
    }
  };
  // Pass 1: d* per cell, clipped at reach.
  const auto segments = static_cast<uint32_t>(plan_.segments.size());
  std::vector<float> best(n, std::numeric_limits<float>::infinity());
  const auto beyond_best = [&](size_t i) { return static_cast<double>(best[i]); };
  for (uint32_t k = 0; k < segments; ++k)
    for_cells_near(k, beyond_best,
                   [&](size_t i, double d) { best[i] = std::min(best[i], static_cast<float>(d)); });
  // Pass 2: count, then fill the candidate lists (CSR).
  std::vector<uint32_t> count(n + 1, 0);
  const auto beyond_candidates = [&](size_t i) { return best[i] + 2 * r + 1e-9; };
  auto is_candidate = [&](size_t i, double d) {
    return best[i] - r <= options_.max_distance_m && d <= beyond_candidates(i);
  };
  for (uint32_t k = 0; k < segments; ++k)
    for_cells_near(k, beyond_candidates, [&](size_t i, double d) {
      if (is_candidate(i, d)) ++count[i + 1];
    });
  begin->assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i) (*begin)[i + 1] = (*begin)[i] + count[i + 1];
  lists->resize((*begin)[n]);
  std::vector<uint32_t> fill(begin->begin(), begin->end() - 1);
  for (uint32_t k = 0; k < segments; ++k)
    for_cells_near(k, beyond_candidates, [&](size_t i, double d) {
      if (is_candidate(i, d)) (*lists)[fill[i]++] = k;
    });
}

void ClosestWallIndex::SortCandidates(const std::vector<uint32_t>& begin,
                                      std::vector<uint32_t>* lists) const {
  // Each list nearest its cell's centre first (see Query), ties in segment order.
  std::vector<std::pair<double, uint32_t>> sorted;
  for (int iy = 0; iy < ny_; ++iy) {
    for (int ix = 0; ix < nx_; ++ix) {
      const size_t i = static_cast<size_t>(iy) * nx_ + ix;
      const Eigen::Vector2d c = CellCentre(ix, iy);
      sorted.clear();
      for (uint32_t j = begin[i]; j < begin[i + 1]; ++j)
        sorted.emplace_back(data_[(*lists)[j]].Distance2(c), (*lists)[j]);
      std::sort(sorted.begin(), sorted.end());
      for (size_t j = 0; j < sorted.size(); ++j) (*lists)[begin[i] + j] = sorted[j].second;
    }
  }
}

void ClosestWallIndex::PackCells(const std::vector<uint32_t>& begin,
                                 const std::vector<uint32_t>& lists) {
  const size_t n = begin.size() - 1;
  cells_.assign(n, Cell{kNone, kNone});
  lists_.clear();
  for (size_t i = 0; i < n; ++i) {
    const uint32_t count = begin[i + 1] - begin[i];
    const uint32_t* list = lists.data() + begin[i];
    if (count <= 2) {
      if (count > 0) cells_[i].a = list[0];
      if (count > 1) cells_[i].b = list[1];
      continue;
    }
    cells_[i] = {static_cast<uint32_t>(lists_.size()), kList | count};
    lists_.insert(lists_.end(), list, list + count);
  }
  lists_.shrink_to_fit();
}

std::optional<ClosestWall> ClosestWallIndex::Query(const Eigen::Vector2d& p) const {
  int ix = 0, iy = 0;
  if (!CellOf(p, &ix, &iy)) return std::nullopt;
  const size_t i = static_cast<size_t>(iy) * nx_ + ix;
  double best = options_.max_distance_m * options_.max_distance_m;
  int64_t best_k = -1;
  double best_u = 0;
  // A list runs nearest the cell's centre c first, and no point of the cell is nearer a
  // segment s than d(s, c) - r. So once a chunk's first candidate is that far beyond the
  // best so far, so is every later one (a raster plan lists dozens of cells' segments).
  constexpr ptrdiff_t kChunk = 8;
  uint32_t held[2];
  const auto [begin, end] = Candidates(cells_[i], held);
  for (const uint32_t* chunk = begin; chunk < end; chunk += kChunk) {
    if (chunk != begin) {
      const Eigen::Vector2d c = CellCentre(ix, iy);
      const double r = 0.5 * options_.cell_m * std::sqrt(2.0) + 1e-6;
      const double beyond = std::sqrt(data_[*chunk].Distance2(c)) - r;
      if (beyond > 0 && beyond * beyond > best) break;
    }
    const uint32_t* chunk_end = end - chunk > kChunk ? chunk + kChunk : end;
    for (const uint32_t* j = chunk; j < chunk_end; ++j) {
      const int64_t k = *j;
      double u = 0;
      const double d2 = data_[k].Distance2(p, &u);
      // Ties go to the higher segment index, whatever the list's order.
      if (d2 < best || (d2 == best && k > best_k)) {
        best = d2;
        best_k = k;
        best_u = u;
      }
    }
  }
  if (best_k < 0) return std::nullopt;
  const SegmentData& s = data_[best_k];
  ClosestWall hit;
  hit.segment = static_cast<uint32_t>(best_k);
  hit.point = s.a + best_u * s.d;
  hit.normal = s.normal;
  hit.distance = std::sqrt(best);
  return hit;
}

bool ClosestWallIndex::StepCrossesWall(const Eigen::Vector2d& p, const Eigen::Vector2d& q) const {
  if (!p.allFinite() || !q.allFinite()) return false;
  auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
    return u.x() * v.y() - u.y() * v.x();
  };
  const Eigen::Vector2d step = q - p;
  // A wall across a piece is within half its length of the piece's middle: a piece no
  // longer than a cell (or than twice the reach) keeps it in the middle cell's list.
  const double piece_m = std::min(options_.cell_m, 2 * options_.max_distance_m);
  const int pieces = static_cast<int>(std::clamp(std::ceil(step.norm() / piece_m), 1.0, 1e4));
  for (int k = 0; k < pieces; ++k) {
    const Eigen::Vector2d a = p + step * (static_cast<double>(k) / pieces);
    const Eigen::Vector2d b = p + step * (static_cast<double>(k + 1) / pieces);
    const Eigen::Vector2d m = 0.5 * (a + b);
    int ix = 0, iy = 0;
    if (!CellOf(m, &ix, &iy)) continue;
    const size_t i = static_cast<size_t>(iy) * nx_ + ix;
    // The piece finds the candidates; each is tried against the whole step, so that a
    // wall crossed where two pieces meet counts.
    uint32_t held[2];
    const auto [begin, end] = Candidates(cells_[i], held);
    for (const uint32_t* j = begin; j < end; ++j) {
      const SegmentData& s = data_[*j];
      const double d1 = cross(step, s.a - p), d2 = cross(step, s.a + s.d - p);
      const double d3 = cross(s.d, p - s.a), d4 = cross(s.d, q - s.a);
      if (d1 * d2 < 0 && d3 * d4 < 0) return true;
    }
  }
  return false;
}

size_t ClosestWallIndex::MemoryBytes() const {
  return cells_.size() * sizeof(Cell) + lists_.size() * sizeof(uint32_t) +
         plan_.segments.size() * (sizeof(Segment) + sizeof(SegmentData)) + grid_.MemoryBytes();
}

std::optional<ClosestWall> BruteForceClosestWall(const FloorPlan& plan, const Eigen::Vector2d& p,
                                                 double max_distance_m) {
  double best = max_distance_m * max_distance_m;
  int64_t best_k = -1;
  for (uint32_t k = 0; k < plan.segments.size(); ++k) {
    const double d2 = (ClosestPointOnSegment(plan.segments[k], p) - p).squaredNorm();
    if (d2 <= best) {
      best = d2;
      best_k = k;
    }
  }
  if (best_k < 0) return std::nullopt;
  return MakeHit(plan, static_cast<uint32_t>(best_k), p);
}

}  // namespace floorpose
