// The live wall points: ADDED / UPDATED / REMOVED bookkeeping, the voxel snapshot that
// feeds registration, and radius queries against a brute-force filter.
#include "core/wall_store.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <tuple>

#include "core/random.h"

namespace floorpose {
namespace {

std::vector<WallPoint> RandomPoints(SplitMix64& rng, size_t n, float lo = -10, float hi = 10) {
  std::vector<WallPoint> out;
  for (size_t i = 0; i < n; ++i) {
    const float a = static_cast<float>(rng.Uniform(-M_PI, M_PI));
    out.push_back(
        {{static_cast<float>(rng.Uniform(lo, hi)), static_cast<float>(rng.Uniform(lo, hi))},
         {std::cos(a), std::sin(a)}});
  }
  return out;
}

// Sorted (x, y) of points, to compare sets regardless of order.
std::vector<std::tuple<float, float>> Sorted(const std::vector<WallPoint>& points) {
  std::vector<std::tuple<float, float>> out;
  for (const WallPoint& w : points) out.emplace_back(w.p.x(), w.p.y());
  std::sort(out.begin(), out.end());
  return out;
}

TEST(WallStoreTest, UpsertReplaceRemoveCounts) {
  SplitMix64 rng(41);
  WallStore store;
  EXPECT_EQ(store.Upsert(1, RandomPoints(rng, 100)), 100u);
  EXPECT_EQ(store.Upsert(2, RandomPoints(rng, 50)), 150u);
  EXPECT_EQ(store.meshes(), 2u);
  EXPECT_TRUE(store.Contains(1));
  // UPDATED replaces the mesh wholesale.
  EXPECT_EQ(store.Upsert(1, RandomPoints(rng, 30)), 80u);
  EXPECT_EQ(store.points(), 80u);
  EXPECT_EQ(store.MeshPoints(1), 30u);
  EXPECT_EQ(store.MeshPoints(2), 50u);
  EXPECT_EQ(store.MeshPoints(99), 0u);
  EXPECT_EQ(store.meshes(), 2u);
  EXPECT_EQ(store.new_points(), 180u);  // every upserted point is new data
  EXPECT_EQ(store.TakeNewPoints(), 180u);
  EXPECT_EQ(store.new_points(), 0u);

  EXPECT_TRUE(store.Remove(2));
  EXPECT_EQ(store.points(), 30u);
  EXPECT_FALSE(store.Contains(2));
  EXPECT_FALSE(store.Remove(2));   // already gone
  EXPECT_FALSE(store.Remove(99));  // never added
  EXPECT_EQ(store.points(), 30u);

  // A mesh may be empty (a surface with no walls) and still be live.
  EXPECT_EQ(store.Upsert(3, {}), 30u);
  EXPECT_TRUE(store.Contains(3));

  store.Clear();
  EXPECT_EQ(store.points(), 0u);
  EXPECT_EQ(store.meshes(), 0u);
  EXPECT_EQ(store.occupied_voxels(), 0u);
  EXPECT_TRUE(store.Snapshot(0).empty());
}

TEST(WallStoreTest, EvictionTakesTheMeshesScannedLongestAgo) {
  SplitMix64 rng(43);
  WallStore store;
  store.Upsert(5, RandomPoints(rng, 10), 300);
  store.Upsert(1, RandomPoints(rng, 10), 100);
  store.Upsert(2, RandomPoints(rng, 10), 100);  // same age as 1: the lower id goes first
  store.Upsert(3, RandomPoints(rng, 10), 200);
  EXPECT_EQ(store.EvictOldest(40), 0u);  // within the bound: nothing
  EXPECT_EQ(store.EvictOldest(25), 2u);
  EXPECT_FALSE(store.Contains(1));
  EXPECT_FALSE(store.Contains(2));
  EXPECT_EQ(store.points(), 20u);
  // The kept mesh stays even when it is the oldest.
  EXPECT_EQ(store.EvictOldest(10, 3), 1u);
  EXPECT_TRUE(store.Contains(3));
  EXPECT_FALSE(store.Contains(5));
  EXPECT_EQ(store.occupied_voxels(), store.Snapshot(0).size());
  EXPECT_EQ(store.EvictOldest(0, 3), 0u);  // nothing else to evict
  EXPECT_EQ(store.points(), 10u);
}

TEST(WallStoreTest, NonFinitePointsAreNeverStored) {
  SplitMix64 rng(42);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  auto points = RandomPoints(rng, 10);
  points.push_back({{nan, 1}, {1, 0}});
  points.push_back({{1, inf}, {1, 0}});
  points.push_back({{1, 1}, {nan, 0}});
  WallStore store;
  EXPECT_EQ(store.Upsert(7, points), 10u);
  EXPECT_EQ(store.MeshPoints(7), 10u);
  for (const auto& p : store.Snapshot(0)) EXPECT_TRUE(p.allFinite());
  const auto all = store.QueryRadius({0, 0}, 100);
  EXPECT_EQ(all.size(), 10u);
  for (const WallPoint& w : all) EXPECT_TRUE(w.p.allFinite() && w.n.allFinite());
  EXPECT_EQ(store.Upsert(8, {{{nan, nan}, {0, 1}}}), 10u);
}

TEST(WallStoreTest, SnapshotIsOnePointPerVoxelBoundedAndDeterministic) {
  SplitMix64 rng(43);
  std::vector<std::vector<WallPoint>> meshes;
  for (int m = 0; m < 6; ++m) meshes.push_back(RandomPoints(rng, 400, -3, 3));

  const double voxel = 0.1;
  WallStore a(voxel), b(voxel);
  for (size_t m = 0; m < meshes.size(); ++m) a.Upsert(m, meshes[m]);
  // The same meshes in another order, with a detour through an update.
  for (size_t m = meshes.size(); m-- > 0;) b.Upsert(m, m == 2 ? meshes[0] : meshes[m]);
  b.Upsert(2, meshes[2]);

  const auto full = a.Snapshot(0);
  EXPECT_EQ(full.size(), a.occupied_voxels());
  EXPECT_EQ(full, b.Snapshot(0));
  EXPECT_EQ(full, a.Snapshot(0));

  // One point per voxel, each one a stored point.
  std::set<std::pair<long, long>> voxels;
  std::set<std::tuple<float, float>> stored;
  for (const auto& mesh : meshes)
    for (const WallPoint& w : mesh) stored.emplace(w.p.x(), w.p.y());
  for (const auto& p : full) {
    EXPECT_TRUE(
        voxels
            .emplace(std::lround(std::floor(p.x() / voxel)), std::lround(std::floor(p.y() / voxel)))
            .second)
        << "two snapshot points in one voxel";
    EXPECT_TRUE(stored.count({static_cast<float>(p.x()), static_cast<float>(p.y())}));
  }

  for (size_t max :
       {size_t{1}, size_t{10}, size_t{333}, full.size() - 1, full.size(), full.size() + 5}) {
    const auto thin = a.Snapshot(max);
    EXPECT_EQ(thin.size(), std::min(max, full.size()));
    EXPECT_EQ(thin, b.Snapshot(max));
    // A subset of the full snapshot, spread over it (not just its first entries).
    for (const auto& p : thin) EXPECT_NE(std::find(full.begin(), full.end(), p), full.end());
  }
  const auto ten = a.Snapshot(10);
  EXPECT_NE(ten.back(), full[9]);
}

// A windowed snapshot (by stamp) is built from the window's meshes only;
// it is what the whole store's snapshot would be had it held those meshes alone.
TEST(WallStoreTest, WindowedSnapshotIsTheSnapshotOfTheWindowsMeshes) {
  SplitMix64 rng(45);
  const double voxel = 0.1;
  WallStore store(voxel);
  std::map<uint64_t, std::pair<std::vector<WallPoint>, int64_t>> live;  // id: points, stamp
  for (uint64_t m = 0; m < 12; ++m) {
    const uint64_t id = (m * 7) % 10;  // some ids written twice
    live[id] = {RandomPoints(rng, 200, -2, 2), static_cast<int64_t>(m) * 10};
    store.Upsert(id, live[id].first, live[id].second);
  }
  store.Remove(3);
  live.erase(3);
  for (const int64_t since : {INT64_MIN, int64_t{0}, int64_t{45}, int64_t{80}, int64_t{200}}) {
    WallStore window(voxel);
    for (const auto& [id, mesh] : live)
      if (mesh.second >= since) window.Upsert(id, mesh.first, mesh.second);
    for (const size_t max : {size_t{0}, size_t{50}})
      EXPECT_EQ(store.Snapshot(max, since), window.Snapshot(max)) << since;
  }
}

TEST(WallStoreTest, QueryRadiusMatchesBruteForce) {
  SplitMix64 rng(44);
  WallStore store(0.05);
  std::map<uint64_t, std::vector<WallPoint>> live;
  for (uint64_t m = 0; m < 8; ++m) {
    live[m] = RandomPoints(rng, 300, -4, 4);
    store.Upsert(m, live[m]);
  }
  // Replace one mesh and remove another: their old points must be gone from queries.
  live[3] = RandomPoints(rng, 100, -4, 4);
  store.Upsert(3, live[3]);
  store.Remove(5);
  live.erase(5);

  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector2f c(static_cast<float>(rng.Uniform(-5, 5)),
                            static_cast<float>(rng.Uniform(-5, 5)));
    const float radius = static_cast<float>(rng.Uniform(0.0, 2.0));
    std::vector<WallPoint> want;
    for (const auto& [id, points] : live)
      for (const WallPoint& w : points)
        if ((w.p - c).squaredNorm() <= radius * radius) want.push_back(w);
    const auto got = store.QueryRadius(c, radius);
    ASSERT_EQ(Sorted(got), Sorted(want)) << "centre (" << c.transpose() << ") radius " << radius;
  }
}

}  // namespace
}  // namespace floorpose
