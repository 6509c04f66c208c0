// Global localization without a wall pick (issue 7): where on the whole plan, at which of
// all headings, do the wall points seen so far fit? Branch-and-bound correlative matching
// after Hess et al. 2016 ("Real-time loop closure in 2D LIDAR SLAM", section V): a
// likelihood grid of the plan's walls, max-pooled into a pyramid whose level h bounds
// every translation of a 2^h-cell square from above, searched best first over every
// rotation. Exact on the grid: no translation scores better than the ones returned.
// Several distinct places come back when the walls seen so far fit more than one (similar
// rooms, thesis section 7.6); telling them apart is the caller's business.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/closest_wall_index.h"
#include "core/floor_plan.h"
#include "core/grid.h"
#include "core/registration.h"
#include "core/se2.h"

namespace floorpose {

struct GlobalSearchOptions {
  double cell_m = 0.1;           // translation step and likelihood grid cell
  double sigma_m = 0.1;          // a point d from a wall scores exp(-d^2 / (2 sigma^2))
  int depth = 7;                 // pyramid levels: the coarsest node is 2^(depth-1) cells wide
  double margin_m = 1.0;         // the grid covers the plan's bounds and this much around them
  double max_cells = 4e6;        // cells grow beyond cell_m to stay within this
  double rotation_step_rad = 0;  // 0: one cell at the cloud's farthest point (Hess eq. 7)
  size_t max_points = 400;       // the cloud is thinned (voxels, then a stride) to this many
  size_t places = 4;             // distinct places returned at most, best first...
  // ...but more, up to crowd_places, while they score at least crowd_ratio of the best: in
  // a hall of repeated bays the first few of many as good are a lottery. 0: no more.
  double crowd_ratio = 0;
  size_t crowd_places = 12;
  double distinct_m = 1.5;                  // places closer than this at the cloud's centre...
  double distinct_rad = 10.0 * M_PI / 180;  // ...and turned less than this are one place
  double min_score = 0.25;                  // mean likelihood a place must reach (0..1)...
  double min_ratio = 0.5;  // ...and this share of the best place's (worse ones tell nothing)
  // WallHeadings: how many alignments of the wall directions, and how wide around each.
  int heading_peaks = 4;
  double heading_spread_rad = 3.0 * M_PI / 180;
};

struct GlobalPlace {
  Se2 T_plan_slam;
  double score = 0;  // mean likelihood of the thinned cloud there, 0..1
  // Filled by RefinePlaces: the mean of min(d, cap)^2 over the whole cloud after ICP
  // (lower fits better), and the share of its points within the inlier threshold.
  double fit_mse = 0;
  double inlier_ratio = 0;
  // ...and how many steps of the wearer's path there cross a wall of the plan (a place
  // that walks the wearer through walls is not where they are).
  uint32_t path_crossings = 0;
  // ...and what share of the cloud's points the wearer could not have seen from the path
  // there, a plan wall in the way (HiddenPoints).
  double hidden_ratio = 0;
  // ...and what share of the plan's walls in clear sight of the path there (within
  // RefineOptions::unseen_reach_m) has no wall point near it (CountUnseenWalls).
  double unseen_ratio = 0;
  uint32_t unseen_expected = 0;  // wall samples in sight (the ratio's denominator)
  // ...and, for a place of rank 0 after the first, how alike the plan around the walk
  // looks under it and under the first (PlanAlike's share; -1: not compared). Walls
  // cannot tell two places apart where the plan looks the same from both walks.
  double alike = -1;
  // RefinePlaces' order: 0 fits and walks through the fewest walls, 1 fits and walks
  // through more, 2 does not fit. Only places of one rank compete on their fits.
  int rank = 0;
};

struct GlobalSearchStats {
  size_t points = 0;     // after thinning
  size_t rotations = 0;  // tried
  size_t nodes = 0;      // bounds evaluated
  double time_ms = 0;    // filled by callers that time it (core has no clock)
  // What the branch and bound cost, in points looked up: at most every point per bound.
  double point_bounds() const { return static_cast<double>(nodes) * static_cast<double>(points); }
};

class GlobalSearch {
 public:
  GlobalSearch(const FloorPlan& plan, GlobalSearchOptions options = {});

  // The best distinct places of the cloud (slam frame) on the plan, best first, each
  // scoring at least min_score. `rotations` (plan frame minus slam frame, radians)
  // restricts the headings tried, e.g. to wall-direction candidates; empty tries all.
  // Non-finite points are ignored; an empty cloud has no place.
  std::vector<GlobalPlace> Search(const std::vector<Eigen::Vector2d>& points_slam,
                                  const std::vector<double>& rotations = {},
                                  GlobalSearchStats* stats = nullptr) const;

  // The headings worth trying for a cloud: where the directions of its walls (local line
  // fits, modulo pi) line up with the plan's (by length, modulo pi), at the best few
  // alignments and half a turn from each, each widened by +-heading_spread_rad. Empty
  // when the cloud shows no straight walls. For Search's `rotations`: a building of
  // right angles needs a few dozen headings instead of every one.
  std::vector<double> WallHeadings(const std::vector<Eigen::Vector2d>& points_slam) const;

  // Mean likelihood of the cloud under T_plan_slam (bilinear-free: nearest cell), 0..1.
  double Score(const std::vector<Eigen::Vector2d>& points_slam, const Se2& T_plan_slam) const;

  const GridGeometry& grid() const { return grid_; }
  const GlobalSearchOptions& options() const { return options_; }
  // The most places Search returns (places, or crowd_places with a crowd_ratio).
  size_t max_places() const {
    return options_.crowd_ratio > 0 ? std::max(options_.places, options_.crowd_places)
                                    : options_.places;
  }
  size_t MemoryBytes() const;

 private:
  struct Node;
  struct Offsets;  // the cloud turned to one heading, as offsets into the pyramid
  // The cloud turned to each of `angles` about its centre.
  std::vector<Offsets> HeadingOffsets(const std::vector<Eigen::Vector2d>& cloud,
                                      const Eigen::Vector2d& centre,
                                      const std::vector<double>& angles) const;
  // The score of the cloud turned as `o` at cell (x, y) of level 0, or for h >= 1 a bound
  // on the scores at every cell of the square [x, x + 2^h) x [y, y + 2^h). A node that
  // cannot reach `need` may stop early with any value below it.
  float Bound(const Offsets& o, int h, int x, int y, float need) const;
  // Search's branch and bound over every heading of `offsets` (the angles in `angles`,
  // about the cloud's `centre`): the places in the order of their scores.
  std::vector<GlobalPlace> BestFirst(const std::vector<Offsets>& offsets,
                                     const std::vector<double>& angles,
                                     const Eigen::Vector2d& centre, GlobalSearchStats& st) const;
  // One cell of arc at reach_m (Hess et al. eq. 7), or rotation_step_rad when set.
  double HeadingStep(double reach_m) const;
  // The pyramid at cell (x, y), for x, y from -pad_ on (0 outside the plan's grid):
  // the likelihood of the cell (level 0) and, for h >= 1, at least the best likelihood of
  // the square [x, x + 2^h) x [y, y + 2^h), in 1/kSteps. Upper levels are only bounds, so
  // they are kept in bytes rounded up, as Cartographer keeps its precomputation grids: the
  // places and their scores are those of float bounds, in well under half the memory.
  static constexpr int kSteps = 255;
  size_t At(int x, int y) const {
    x += pad_;
    y += pad_;
    return x < 0 || y < 0 || x >= stride_ || y >= rows_
               ? SIZE_MAX
               : static_cast<size_t>(y) * static_cast<size_t>(stride_) + static_cast<size_t>(x);
  }
  float Likelihood(int x, int y) const {
    const size_t i = At(x, y);
    return i == SIZE_MAX ? 0.0f : likelihood_[i];
  }

  GlobalSearchOptions options_;
  std::vector<double> plan_directions_;  // wall length per degree of direction, modulo pi
  GridGeometry grid_;
  int pad_ = 0, stride_ = 0, rows_ = 0;
  std::vector<float> likelihood_;             // level 0
  std::vector<std::vector<uint8_t>> bounds_;  // levels 1 .. depth - 1
};

// How RefinePlaces scores and orders places.
struct RefineOptions {
  double cap_m = 0.2;                       // distances capped here in fit_mse (EvaluateFit)
  double distinct_m = 1.5;                  // places converging within this at the cloud's
  double distinct_rad = 10.0 * M_PI / 180;  // centre and turned less than this are merged
  double path_margin_m = 0;  // a step crossing a wall this close to its ends does not count
  // A point the wearer could not have seen from the path under a place (HiddenPoints
  // within this reach: the headset's range and some drift) adds a miss, cap_m squared, to
  // the place's fit_mse. 0: no sight check.
  double sight_reach_m = 0;
  double sight_standoff_m = 0.3;  // the line of sight stops this short of the point
  double sight_allowance = 0.1;   // the share of hidden points that costs nothing
  // The plan's walls in clear sight within this reach of the path, but with no wall point
  // near them (CountUnseenWalls): the samples missed beyond unseen_allowance of those in
  // sight, as a share of those in sight (at least unseen_min_samples: a few samples tell
  // little), add unseen_weight misses (cap_m squared) per whole share to fit_mse. A
  // look-alike puts the walls seen on some of its walls, but walks the wearer past others
  // nobody saw. 0: no such check.
  double unseen_reach_m = 0;
  double unseen_allowance = 0.5;
  double unseen_weight = 0.5;
  uint32_t unseen_min_samples = 20;
  // A place under which more than this share of those samples (unseen_min_samples or
  // more) went unseen does not fit, however its points lie: true places rarely miss more
  // than three quarters of the walls they walk past.
  double unseen_max_ratio = 0.8;
  // Places of rank 0 after the first are compared with it (PlanAlike) over the plan's
  // walls in sight within this reach of the path. 0: not compared.
  double alike_reach_m = 0;
  double min_inliers = 0;  // places fitting a smaller share of the cloud go last
};

// The search's places polished: each refined by ICP on the plan's walls from where the
// search put it (the grid's 10 cm cells and heading steps leave a few centimetres and a
// fraction of a degree), then scored on the whole cloud with distances capped at cap_m
// (EvaluateFit), and the wearer's path (slam positions, in order) checked for steps
// through the plan's walls. The grid's scores blur a near miss and a right place; the
// refined fits tell them apart. Places that converge onto one another are merged. The
// order, best first: places that fit (min_inliers) before those that do not; among them,
// those whose path crosses no more walls than the fewest of their group first; best fit
// first within each. `ranked`, places an earlier call returned on the same cloud and
// path, are ranked with the new ones without being refined and scored again.
std::vector<GlobalPlace> RefinePlaces(const std::vector<GlobalPlace>& places,
                                      const std::vector<Eigen::Vector2d>& points_slam,
                                      const std::vector<Eigen::Vector2d>& path_slam,
                                      const ClosestWallIndex& index, const IcpOptions& icp,
                                      const RefineOptions& options = {},
                                      const std::vector<GlobalPlace>& ranked = {});

// The half-turn twins of a place: where the plan's own walls in sight of the walk there
// (WallSamplesInSight of the path, slam frame, under `place`) fit again at the headings
// half a turn from it (those of `headings` within distinct_rad of it, or that heading
// alone), best first. Grid places, to be refined on the wearer's walls. A hall that looks
// the same both ways round has one, which the grid's few best places on the wearer's
// drifting walls often leave out; the plan's walls have no drift and no clutter. `stats`:
// the search's, as Search gives them.
std::vector<GlobalPlace> HalfTurnTwins(const GlobalSearch& search, const FloorPlan& plan,
                                       const Se2& place,
                                       const std::vector<Eigen::Vector2d>& path_slam,
                                       const std::vector<double>& headings,
                                       const WallSampleOptions& in_sight,
                                       GlobalSearchStats* stats = nullptr);

// How alike the plan looks from the wearer's walk under two places: the plan's walls in
// sight of the path (slam frame) under `a` (WallSamplesInSight within reach_m, every
// 0.25 m), moved to where `b` puts them (b a^-1), and the share of them within match_m of
// a wall of the plan; the same from b to a; the lower of the two shares. 1 for a room's
// half-turn twin about its centre or a copy of a room, lower the more of what the walk
// passes differs (a door, a corridor on one side only). `samples` is the smaller count;
// with none in sight the share is 0.
struct PlanAlikeness {
  double share = 0;
  uint32_t samples = 0;
};
PlanAlikeness PlanAlike(const std::vector<Eigen::Vector2d>& path_slam, const Se2& a, const Se2& b,
                        const ClosestWallIndex& index, double reach_m, double match_m = 0.3,
                        double end_margin_m = 0);

}  // namespace floorpose
