// `floorpose bench registration`: the median time of one full registration per method
// (icp, ik, hough) and of a brute-force closest-wall baseline, for 1k, 10k and 100k wall
// points against a real floor plan of at least 500 segments; the closest-wall query time
// (index against brute force); and the index's memory for a 230 x 100 m building.
// docs/performance.md holds the table this prints and the command that printed it.
//
// Timing is a plain median of N runs with std::chrono::steady_clock: registration takes
// milliseconds, far above the clock's resolution, and a median shrugs off the odd
// preempted run on a shared machine.
#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>

#include <unistd.h>
#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/closest_wall_index.h"
#include "core/floor_plan.h"
#include "core/random.h"
#include "core/registration.h"
#include "core/se2.h"
#include "platform/engine.h"
#include "platform/floor_plan_io.h"
#include "platform/state_file.h"
#include "tools/floorpose/bench_peers.h"
#include "tools/floorpose/commands.h"

namespace floorpose::tools {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct BenchOptions {
  std::string plan;  // empty: the largest plan under $FLOORPOSE_DATA/floorplans
  bool json = false;
  int repetitions = 7;
  size_t min_segments = 500;
};

constexpr double kNoiseM = 0.02;      // wall points: Gaussian noise per axis
constexpr double kErrorRad = 0.0175;  // initial guess: the truth turned by 1 degree
constexpr double kErrorM = 0.3;  // ... and shifted by 0.3 m diagonally, about the cloud's centre
constexpr double kPeerSampleM = 0.02;  // a peer's target: the walls sampled this often
constexpr double kVoxelM = 0.1;        // icp_voxel_means: icp.voxel_m
constexpr double kTileGapM = 5.0;      // between tiled copies of the plan
constexpr uint64_t kSeed = 20240601;   // the same clouds on every run

double Ms(Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Times fn() `repetitions` times; the median in milliseconds.
template <typename Fn>
double MedianMs(int repetitions, Fn&& fn) {
  std::vector<double> ms;
  for (int i = 0; i < repetitions; ++i) {
    const auto start = Clock::now();
    fn();
    ms.push_back(Ms(Clock::now() - start));
  }
  return Median(ms);
}

// The plan with the most segments among $FLOORPOSE_DATA/floorplans/*/*.{geojson,txt}
// (MLSTRUCT 302 and 848 tie at 320; 848, the bigger building, wins on wall length).
std::optional<std::string> LargestDataPlan(std::string* error) {
  const char* data = std::getenv("FLOORPOSE_DATA");
  if (!data || !*data) {
    *error = "no --plan given and FLOORPOSE_DATA is not set (the directory holding floorplans/)";
    return std::nullopt;
  }
  std::optional<std::string> best;
  size_t best_segments = 0;
  double best_length = 0;
  std::error_code ec;
  std::vector<fs::path> files;
  for (const auto& dir : fs::directory_iterator(fs::path(data) / "floorplans", ec)) {
    if (!dir.is_directory()) continue;
    for (const auto& f : fs::directory_iterator(dir.path(), ec)) {
      const std::string name = f.path().filename().string();
      if (name.rfind("LICENSE", 0) == 0) continue;
      if (f.path().extension() == ".geojson" || f.path().extension() == ".txt")
        files.push_back(f.path());
    }
  }
  std::sort(files.begin(), files.end());  // ties go to the first name: stable output
  for (const fs::path& f : files) {
    const FloorPlanParse parse = platform::LoadFloorPlan(f.string());
    if (!parse.ok()) continue;
    double length = 0;
    for (const Segment& s : parse.plan.segments) length += s.Length();
    // Most segments; on a tie, most wall length (the bigger building).
    if (parse.plan.segments.size() > best_segments ||
        (parse.plan.segments.size() == best_segments && length > best_length + 1e-6)) {
      best_segments = parse.plan.segments.size();
      best_length = length;
      best = f.string();
    }
  }
  if (!best) *error = std::string("no floor plan under ") + data + "/floorplans";
  return best;
}

// Copies of `plan` side by side along x, kTileGapM apart, until it has min_segments.
FloorPlan Tile(const FloorPlan& plan, size_t min_segments, int* copies) {
  *copies = static_cast<int>(
      std::max<size_t>(1, (min_segments + plan.segments.size() - 1) / plan.segments.size()));
  const double step = plan.max.x() - plan.min.x() + kTileGapM;
  std::vector<Segment> walls;
  for (int k = 0; k < *copies; ++k)
    for (const Segment& s : plan.segments) {
      const Eigen::Vector2d shift(k * step, 0);
      walls.push_back({s.a + shift, s.b + shift});
    }
  return MakeFloorPlan(plan.id + (*copies > 1 ? "-tiled" : ""), std::move(walls)).plan;
}

// n points drawn uniformly along all walls (by length), with their wall's normal (random
// sign), moved to the slam frame.
struct Cloud {
  std::vector<Eigen::Vector2d> points, normals;
  Eigen::Vector2d centre_plan = Eigen::Vector2d::Zero();
};

Cloud SampleWalls(const FloorPlan& plan, size_t n, const Se2& T_slam_plan, SplitMix64& rng) {
  std::vector<double> cumulative;
  double total = 0;
  for (const Segment& s : plan.segments) cumulative.push_back(total += s.Length());
  Cloud cloud;
  for (size_t i = 0; i < n; ++i) {
    const double at = rng.Uniform(0, total);
    const size_t k = std::min<size_t>(
        plan.segments.size() - 1,
        std::upper_bound(cumulative.begin(), cumulative.end(), at) - cumulative.begin());
    const Segment& s = plan.segments[k];
    const double u = rng.Uniform();
    const Eigen::Vector2d p = s.a + u * (s.b - s.a);
    const Eigen::Vector2d noise(rng.Gaussian(), rng.Gaussian());
    cloud.points.push_back(T_slam_plan * (p + kNoiseM * noise));
    cloud.normals.push_back(T_slam_plan.R() * s.Normal() * (rng.Uniform() < 0.5 ? -1.0 : 1.0));
    cloud.centre_plan += p;
  }
  cloud.centre_plan /= static_cast<double>(n);
  return cloud;
}

// The baseline: plain point-to-line ICP (Gauss-Newton about the centroid, eq. 4.4; every
// point every iteration; no levels, kernel or rejection), the closest wall of each point
// from `closest`, for exactly `iterations` iterations.
template <typename Closest>
Se2 PlainIcp(const std::vector<Eigen::Vector2d>& points, const Se2& initial, int iterations,
             double max_correspondence_m, Closest&& closest) {
  Se2 T = initial;
  for (int it = 0; it < iterations; ++it) {
    const Eigen::Matrix2d R = T.R();
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
    struct Pair {
      Eigen::Vector2d p, n;
      double r;
    };
    std::vector<Pair> pairs;
    pairs.reserve(points.size());
    for (const Eigen::Vector2d& q : points) {
      const Eigen::Vector2d p = R * q + T.t;
      const std::optional<ClosestWall> hit = closest(p);
      if (!hit || hit->distance > max_correspondence_m) continue;
      pairs.push_back({p, hit->normal, hit->normal.dot(p - hit->point)});
      centroid += p;
    }
    if (pairs.size() < 3) break;
    centroid /= static_cast<double>(pairs.size());
    for (const Pair& q : pairs) {
      const Eigen::Vector2d p = q.p - centroid;
      const Eigen::Vector3d a(p.x() * q.n.y() - p.y() * q.n.x(), q.n.x(), q.n.y());
      H += a * a.transpose();
      g += a * q.r;
    }
    const Eigen::Vector3d delta = -H.ldlt().solve(g);
    if (!delta.allFinite()) break;
    const Se2 rotation{delta(0), {0, 0}};
    T = Se2{delta(0), centroid + delta.tail<2>() - rotation.R() * centroid} * T;
  }
  return T;
}

// "model name" from /proc/cpuinfo, or "unknown".
std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) != 0) continue;
    const auto colon = line.find(':');
    if (colon != std::string::npos) return line.substr(line.find_first_not_of(' ', colon + 1));
  }
  return "unknown";
}

double LoadAverage() {
  std::ifstream in("/proc/loadavg");
  double load = -1;
  in >> load;
  return load;
}

// A 230 x 100 m building: a grid of 6 x 5 m rooms (38 x 20), every wall one line with a
// 1 m door in its middle, so each room side is two segments.
FloorPlan SyntheticBuilding() {
  constexpr int kColumns = 38, kRows = 20;
  constexpr double kRoomW = 6.0, kRoomH = 5.0, kDoor = 1.0;
  std::vector<Segment> walls;
  auto wall_with_door = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d mid = 0.5 * (a + b), d = (b - a).normalized() * (0.5 * kDoor);
    walls.push_back({a, mid - d});
    walls.push_back({mid + d, b});
  };
  for (int r = 0; r <= kRows; ++r)
    for (int c = 0; c < kColumns; ++c)
      wall_with_door({c * kRoomW, r * kRoomH}, {(c + 1) * kRoomW, r * kRoomH});
  for (int c = 0; c <= kColumns; ++c)
    for (int r = 0; r < kRows; ++r)
      wall_with_door({c * kRoomW, r * kRoomH}, {c * kRoomW, (r + 1) * kRoomH});
  return MakeFloorPlan("synthetic-230x100", std::move(walls)).plan;
}

struct Row {
  std::string method;
  size_t points = 0;
  double median_ms = 0;
  int runs = 0;
  std::string extra_text;                                           // for the table
  nlohmann::ordered_json extra = nlohmann::ordered_json::object();  // more fields of its line
};

// The rows measured, in order; with --json each is printed as it comes.
class Rows {
 public:
  Rows(bool json, size_t segments) : json_(json), segments_(segments) {}

  void Add(Row row) {
    if (json_) {
      nlohmann::ordered_json line = {{"method", row.method},
                                     {"points", row.points},
                                     {"median_ms", row.median_ms},
                                     {"runs", row.runs},
                                     {"segments", segments_}};
      line.update(row.extra);
      std::printf("%s\n",
                  line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
      std::fflush(stdout);
    }
    rows_.push_back(std::move(row));
  }
  const std::vector<Row>& rows() const { return rows_; }

 private:
  bool json_;
  size_t segments_;
  std::vector<Row> rows_;
};

// A row for a registration result: its iterations and its error against the truth at the
// cloud's centre (cm) and in rotation (degrees).
Row ResultRow(std::string method, size_t n, double ms, int runs, int iterations, const Se2& T,
              const Se2& truth, const Eigen::Vector2d& centre_plan) {
  const double cm = 100 * ((T * truth.Inverse()) * centre_plan - centre_plan).norm();
  const double deg = std::abs(WrapAngle(T.theta - truth.theta)) * 180 / M_PI;
  char text[128];
  std::snprintf(text, sizeof text, "%4d iterations, %.2f cm, %.3f deg off", iterations, cm, deg);
  return {std::move(method),
          n,
          ms,
          runs,
          text,
          {{"iterations", iterations}, {"error_cm", cm}, {"error_deg", deg}}};
}

// Every registration method on one cloud, then the plain ICP loop for as many iterations
// as icp took, on the index and by brute force (the query's share of the time).
void BenchRegistrations(const Cloud& cloud, const Se2& truth, const FloorPlan& plan,
                        const ClosestWallIndex& index, const BenchOptions& o,
                        [[maybe_unused]] const PclPointToPlaneIcp* peer, Rows& rows) {
  const size_t n = cloud.points.size();
  const RegistrationOptions defaults;
  // The initial guess: the truth turned and shifted about the cloud's centre.
  const Se2 turn{kErrorRad, cloud.centre_plan - Se2{kErrorRad, {0, 0}}.R() * cloud.centre_plan +
                                Eigen::Vector2d(kErrorM, kErrorM) / std::sqrt(2.0)};
  const Se2 initial = turn * truth;
  int icp_iterations = 0;
  [[maybe_unused]] double icp_ms = 0;
  for (RegistrationMethod m :
       {RegistrationMethod::kIcp, RegistrationMethod::kIk, RegistrationMethod::kHough}) {
    RegistrationOptions options = defaults;
    options.method = m;
    RegistrationResult r;
    const double ms = MedianMs(
        o.repetitions, [&] { r = Register(cloud.points, cloud.normals, index, initial, options); });
    if (m == RegistrationMethod::kIcp) {
      icp_iterations = static_cast<int>(r.iterations);
      icp_ms = ms;
    }
    rows.Add(ResultRow(ToString(m), n, ms, o.repetitions, static_cast<int>(r.iterations),
                       r.T_plan_slam, truth, cloud.centre_plan));
  }
  {
    // ICP on the cloud's voxel means (icp.voxel_m), as for a laser's dense windows.
    RegistrationOptions options = defaults;
    options.icp.voxel_m = kVoxelM;
    RegistrationResult r;
    const double ms = MedianMs(
        o.repetitions, [&] { r = Register(cloud.points, cloud.normals, index, initial, options); });
    rows.Add(ResultRow("icp_voxel_means", n, ms, o.repetitions, static_cast<int>(r.iterations),
                       r.T_plan_slam, truth, cloud.centre_plan));
  }
#if FLOORPOSE_BENCH_PEERS
  if (peer) {
    // PCL's point-to-plane ICP from the same guess, with our correspondence reach,
    // iteration limit and translation step for convergence.
    PeerFit fit;
    const int runs = n >= 100000 ? std::min(o.repetitions, 3) : o.repetitions;
    const double ms = MedianMs(runs, [&] { fit = peer->Align(cloud.points, initial); });
    Row row = ResultRow("pcl_icp_plane", n, ms, runs, fit.iterations, fit.T_plan_slam, truth,
                        cloud.centre_plan);
    const double ratio = ms / icp_ms;
    char text[64];
    std::snprintf(text, sizeof text, ", %.1fx icp's time%s", ratio,
                  fit.converged ? "" : ", did not converge");
    row.extra_text += text;
    row.extra["ratio_to_icp"] = ratio;
    row.extra["converged"] = fit.converged;
    rows.Add(std::move(row));
  }
#endif
  // At 100k points brute force takes seconds a run: one run is enough to see it.
  const double max_corr = defaults.icp.max_correspondence_m;
  const double max_distance = index.options().max_distance_m;
  for (bool brute : {false, true}) {
    Se2 T;
    const int runs = brute && n >= 100000 ? 1 : o.repetitions;
    const double ms = MedianMs(runs, [&] {
      T = brute ? PlainIcp(cloud.points, initial, icp_iterations, max_corr,
                           [&](const Eigen::Vector2d& p) {
                             return BruteForceClosestWall(plan, p, max_distance);
                           })
                : PlainIcp(cloud.points, initial, icp_iterations, max_corr,
                           [&](const Eigen::Vector2d& p) { return index.Query(p); });
    });
    rows.Add(ResultRow(brute ? "icp_loop_bruteforce" : "icp_loop_index", n, ms, runs,
                       icp_iterations, T, truth, cloud.centre_plan));
  }
}

// Closest-wall queries at the given points (where ICP asks), on the index and by brute
// force (a tenth of them: it is slow).
void BenchQueries(const std::vector<Eigen::Vector2d>& queries, const FloorPlan& plan,
                  const ClosestWallIndex& index, const BenchOptions& o, Rows& rows) {
  const double max_distance = index.options().max_distance_m;
  for (bool brute : {false, true}) {
    const size_t count = brute ? queries.size() / 10 : queries.size();
    size_t found = 0;
    const double ms = MedianMs(o.repetitions, [&] {
      found = 0;
      for (size_t i = 0; i < count; ++i)
        found += (brute ? BruteForceClosestWall(plan, queries[i], max_distance)
                        : index.Query(queries[i]))
                     .has_value();
    });
    char text[128];
    const double ns = 1e6 * ms / static_cast<double>(count);
    std::snprintf(text, sizeof text, "%.1f ns per query (%zu queries a run)", ns, count);
    rows.Add({brute ? "query_bruteforce" : "query_index",
              count,
              ms,
              o.repetitions,
              text,
              {{"ns_per_query", ns}}});
  }
}

// Index memory and build time for a building of 230 x 100 m.
void BenchIndexBuild(const ClosestWallIndex::Options& index_options, const BenchOptions& o,
                     Rows& rows) {
  const FloorPlan building = SyntheticBuilding();
  size_t memory = 0;
  const int build_runs = std::max(1, o.repetitions / 2);
  const double build_ms = MedianMs(
      build_runs, [&] { memory = ClosestWallIndex(building, index_options).MemoryBytes(); });
  char text[192];
  std::snprintf(text, sizeof text,
                "%.1f MB for %s (%zu segments, %.0f x %.0f m), cell %.2f m, max distance %.1f m",
                memory / 1e6, building.id.c_str(), building.segments.size(),
                building.max.x() - building.min.x(), building.max.y() - building.min.y(),
                index_options.cell_m, index_options.max_distance_m);
  rows.Add({"index_build",
            0,
            build_ms,
            build_runs,
            text,
            {{"memory_bytes", memory},
             {"plan", building.id},
             {"plan_segments", building.segments.size()},
             {"cell_m", index_options.cell_m},
             {"max_distance_m", index_options.max_distance_m}}});
}

void PrintRegistrationTable(const std::string& plan_path, const FloorPlan& original,
                            const FloorPlan& plan, int copies, const ClosestWallIndex& index,
                            const PclPointToPlaneIcp* peer, const std::vector<Row>& rows) {
  const ClosestWallIndex::Options& index_options = index.options();
  std::printf("floorpose bench registration\n");
  std::printf("plan:     %s: %zu segments", plan_path.c_str(), original.segments.size());
  if (copies > 1)
    std::printf(", tiled %d copies side by side along x, %.0f m apart", copies, kTileGapM);
  std::printf(" -> %zu segments, %.1f x %.1f m\n", plan.segments.size(),
              plan.max.x() - plan.min.x(), plan.max.y() - plan.min.y());
  std::printf("index:    cell %.2f m, max distance %.1f m, %.2f MB\n", index_options.cell_m,
              index_options.max_distance_m, index.MemoryBytes() / 1e6);
  std::printf(
      "points:   drawn uniformly along all walls, %.0f cm noise per axis; initial guess\n"
      "          the truth turned %.0f degree and shifted %.1f m about the cloud's "
      "centre; default options\n",
      100 * kNoiseM, kErrorRad * 180 / M_PI, kErrorM);
  std::printf(
      "baseline: icp_loop_bruteforce is a plain point-to-line ICP loop (every point every\n"
      "          iteration; no levels, kernel or rejection) with BruteForceClosestWall,\n"
      "          run for as many iterations as icp reported; icp_loop_index is the same\n"
      "          loop on the index; icp_voxel_means is icp on the cloud's 10 cm voxel\n"
      "          means, each weighing as its voxel's points (icp.voxel_m 0.1)\n");
  if (peer)
    std::printf(
        "peer:     pcl_icp_plane is PCL's IterativeClosestPointWithNormals, point-to-plane\n"
        "          Levenberg-Marquardt on x, y and heading, against %zu wall points every\n"
        "          %.0f cm with their normals (k-d tree built once); icp's reach, iteration\n"
        "          limit and translation step\n",
        peer->target_points(), 100 * kPeerSampleM);
  else
    std::printf(
        "peer:     none in this build (cmake -DFLOORPOSE_BENCH_PEERS=ON with libpcl-dev\n"
        "          runs PCL's point-to-plane ICP beside ours)\n");
  std::printf("machine:  %u cores (hardware_concurrency), %s, load average %.2f\n",
              std::thread::hardware_concurrency(), CpuModel().c_str(), LoadAverage());
  std::printf("timing:   median of the runs shown, one thread\n\n");
  std::printf("%-20s %8s %12s %5s  %s\n", "method", "points", "median ms", "runs", "");
  for (const Row& r : rows)
    std::printf("%-20s %8zu %12.3f %5d  %s\n", r.method.c_str(), r.points, r.median_ms, r.runs,
                r.extra_text.c_str());
}

int RunBenchRegistration(const BenchOptions& o) {
  if (o.repetitions < 1) {
    spdlog::error("--repetitions must be at least 1");
    return 2;
  }
  std::string plan_path = o.plan, error;
  if (plan_path.empty()) {
    const auto found = LargestDataPlan(&error);
    if (!found) {
      spdlog::error("{}", error);
      return 2;
    }
    plan_path = *found;
  }
  const FloorPlanParse parse = platform::LoadFloorPlan(plan_path);
  if (!parse.ok()) {
    spdlog::error("{}", parse.error);
    return 1;
  }
  int copies = 1;
  const FloorPlan plan = Tile(parse.plan, o.min_segments, &copies);
  const ClosestWallIndex index(plan, ClosestWallIndex::Options{});
  Rows rows(o.json, plan.segments.size());
  const PclPointToPlaneIcp* peer = nullptr;
#if FLOORPOSE_BENCH_PEERS
  const IcpOptions icp;
  const PclPointToPlaneIcp pcl(plan, kPeerSampleM, icp.max_correspondence_m,
                               static_cast<int>(icp.max_iterations), icp.converge_translation_m);
  peer = &pcl;
#endif
  SplitMix64 rng(kSeed);
  const Se2 T_slam_plan{0.7, {-12.0, 31.0}};  // any transform: slam and plan differ
  const Se2 truth = T_slam_plan.Inverse();
  Cloud largest;
  for (size_t n : {size_t{1000}, size_t{10000}, size_t{100000}}) {
    Cloud cloud = SampleWalls(plan, n, T_slam_plan, rng);
    BenchRegistrations(cloud, truth, plan, index, o, peer, rows);
    if (n == 100000) largest = std::move(cloud);
  }
  std::vector<Eigen::Vector2d> queries;
  for (const Eigen::Vector2d& p : largest.points) queries.push_back(truth * p);
  BenchQueries(queries, plan, index, o, rows);
  BenchIndexBuild(index.options(), o, rows);
  if (!o.json)
    PrintRegistrationTable(plan_path, parse.plan, plan, copies, index, peer, rows.rows());
  return 0;
}

// What a state snapshot costs the daemon (daemon/daemon.cc MaybeSnapshot): the io thread
// copies the state (Engine::SaveState), the snapshot thread writes it (serialise, fsync,
// rename). Wall stores of 10k to 1M points, made of 4 m wall meshes fed as mesh deltas.
int RunBenchSnapshot(const BenchOptions& o) {
  if (spdlog::get_level() > spdlog::level::debug) spdlog::set_level(spdlog::level::warn);
  const fs::path dir =
      fs::temp_directory_path() / ("floorpose-bench-snapshot-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "plan.txt") << "1\n0 0 4 0\n";
  v1::FloorposedConfig config;
  config.set_plan_path((dir / "plan.txt").string());
  config.set_headset_frame("zup");
  config.mutable_dds()->set_device_id("bench");
  if (!o.json) {
    std::printf("floorpose bench snapshot: state of a wall store of N points, median of %d\n",
                o.repetitions);
    std::printf("%10s %10s %16s %16s %12s\n", "points", "meshes", "SaveState ms", "write+fsync ms",
                "file MB");
  }
  for (size_t target : {size_t{10'000}, size_t{100'000}, size_t{1'000'000}}) {
    platform::Engine engine(
        config, [](platform::Topic, const google::protobuf::Message&) {},
        [] { return int64_t{0}; });
    if (const std::string e = engine.Start(); !e.empty()) {
      std::fprintf(stderr, "bench snapshot: %s\n", e.c_str());
      return 1;
    }
    for (uint64_t id = 1; engine.store().points() < target; ++id) {
      // A 4 x 2.5 m wall, one per mesh, walls 0.5 m apart.
      v1::MeshDelta m;
      m.set_mesh_id(id);
      m.set_change(v1::MeshDelta::ADDED);
      const float y = 0.5f * static_cast<float>(id);
      for (float v : {0.f, y, 0.f, 4.f, y, 0.f, 4.f, y, 2.5f, 0.f, y, 2.5f}) m.add_vertices(v);
      for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.add_triangles(i);
      engine.OnMeshDelta({"bench", id, 0, m.SerializeAsString()});
    }
    v1::StateSnapshot snapshot;
    const double save_ms = MedianMs(o.repetitions, [&] { snapshot = engine.SaveState(); });
    std::string error;
    const std::string path = (dir / "bench.snapshot").string();
    const double write_ms = MedianMs(o.repetitions, [&] {
      if (!platform::WriteStateFile(path, snapshot, &error))
        std::fprintf(stderr, "%s\n", error.c_str());
    });
    const double mb = static_cast<double>(fs::file_size(path)) / 1e6;
    if (o.json)
      std::printf("%s\n", nlohmann::ordered_json({{"points", engine.store().points()},
                                                  {"meshes", engine.store().meshes()},
                                                  {"save_state_ms", save_ms},
                                                  {"write_ms", write_ms},
                                                  {"file_mb", mb}})
                              .dump()
                              .c_str());
    else
      std::printf("%10zu %10zu %16.2f %16.2f %12.2f\n", engine.store().points(),
                  engine.store().meshes(), save_ms, write_ms, mb);
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
  return 0;
}

}  // namespace

Run AddBenchCommand(CLI::App& app) {
  app.require_subcommand(1);
  auto o = std::make_shared<BenchOptions>();
  CLI::App* registration = app.add_subcommand(
      "registration", "time icp, ik, hough and a brute-force baseline at 1k, 10k, 100k points");
  registration->add_option(
      "--plan", o->plan,
      "floor plan (.geojson or .txt); default: the one with the most segments under "
      "$FLOORPOSE_DATA/floorplans");
  registration->add_flag("--json", o->json, "one JSON object per line per method and size");
  registration->add_option("--repetitions", o->repetitions, "runs per measurement (median)")
      ->capture_default_str();
  registration
      ->add_option("--min-segments", o->min_segments,
                   "tile the plan side by side until it has this many segments")
      ->capture_default_str();
  CLI::App* snapshot = app.add_subcommand(
      "snapshot", "time the state snapshot (copy on the io thread, write) at 10k to 1M points");
  snapshot->add_flag("--json", o->json, "one JSON object per line per store size");
  snapshot->add_option("--repetitions", o->repetitions, "runs per measurement (median)")
      ->capture_default_str();
  Run daemon = AddBenchDaemonCommand(app);
  CLI::App* daemon_command = app.get_subcommand("daemon");
  Run route = AddBenchRouteCommand(app);
  CLI::App* route_command = app.get_subcommand("route");
  Run dashboard = AddBenchDashboardCommand(app);
  CLI::App* dashboard_command = app.get_subcommand("dashboard");
  Run global = AddBenchGlobalCommand(app);
  CLI::App* global_command = app.get_subcommand("global");
  return [o, registration, snapshot, daemon, daemon_command, route, route_command, dashboard,
          dashboard_command, global, global_command] {
    if (dashboard_command->parsed()) return dashboard();
    if (global_command->parsed()) return global();
    if (snapshot->parsed()) return RunBenchSnapshot(*o);
    if (daemon_command->parsed()) return daemon();
    if (route_command->parsed()) return route();
    if (!registration->parsed()) return 2;
    return RunBenchRegistration(*o);
  };
}

}  // namespace floorpose::tools
