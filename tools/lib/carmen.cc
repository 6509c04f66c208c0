#include "tools/lib/carmen.h"

#include <zlib.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

#include "tools/lib/simulate_recording.h"

namespace floorpose::tools {
namespace {

constexpr size_t kMaxLogBytes = size_t{1} << 30;  // decompressed
constexpr size_t kMaxBeams = 4096;

// Whitespace-separated fields of one line.
std::vector<std::string_view> Fields(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

bool ToDouble(std::string_view s, double* v) {
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), *v);
  return ec == std::errc() && ptr == s.data() + s.size() && std::isfinite(*v);
}

Se2 ToSe2(const sim::TimedPose& p) { return {p.heading, p.position}; }
Pose2 ToPose(const Se2& T, double z) { return {T.t, T.theta, z}; }

// a + u (b - a) for poses, the heading the short way round.
Se2 Lerp(const Se2& a, const Se2& b, double u) {
  return {WrapAngle(a.theta + u * WrapAngle(b.theta - a.theta)), a.t + u * (b.t - a.t)};
}

// A time series of poses, read at any time: linear between entries, clamped at the ends.
class Track {
 public:
  explicit Track(const std::vector<sim::TimedPose>& poses) : poses_(poses) {}
  Se2 At(double t) const {
    const auto it = After(t);
    if (it == poses_.begin()) return ToSe2(poses_.front());
    if (it == poses_.end()) return ToSe2(poses_.back());
    const sim::TimedPose& a = *(it - 1);
    const sim::TimedPose& b = *it;
    return Lerp(ToSe2(a), ToSe2(b), (t - a.t_s) / (b.t_s - a.t_s));
  }
  // How long the odometry is silent about t: the time between the readings around it (0
  // before the first and after the last).
  double Gap(double t) const {
    const auto it = After(t);
    if (it == poses_.begin() || it == poses_.end()) return 0.0;
    return it->t_s - (it - 1)->t_s;
  }
  // The last entry at or before t (the reading a scan was paired with), else the first.
  Se2 LastAt(double t) const {
    const auto it = After(t);
    return ToSe2(it == poses_.begin() ? poses_.front() : *(it - 1));
  }

 private:
  // The first entry after t.
  std::vector<sim::TimedPose>::const_iterator After(double t) const {
    return std::upper_bound(poses_.begin(), poses_.end(), t,
                            [](double v, const sim::TimedPose& p) { return v < p.t_s; });
  }

  const std::vector<sim::TimedPose>& poses_;
};

// Piecewise-linear map between two increasing clocks given at the same knots.
double MapClock(const std::vector<double>& from, const std::vector<double>& to, double t) {
  if (t <= from.front()) return to.front() + (t - from.front());
  if (t >= from.back()) return to.back() + (t - from.back());
  const size_t i = std::upper_bound(from.begin(), from.end(), t) - from.begin();
  const double u = (t - from[i - 1]) / (from[i] - from[i - 1]);
  return to[i - 1] + u * (to[i] - to[i - 1]);
}

// A scan's beam end points in the odometry ("slam") frame: which readings are usable
// (not "no return", not too near) and which neighbours are joined into one wall (no
// range jump between them).
struct ScanEnds {
  std::vector<Eigen::Vector2d> ends;
  std::vector<uint8_t> valid;
  std::vector<uint8_t> joined;  // end i to end i + 1
  size_t dropped = 0;           // readings not valid
};

ScanEnds EndPoints(const CarmenScan& scan, const Se2& T_slam_robot, double max_range,
                   const CarmenImportOptions& o) {
  const size_t n = scan.ranges.size();
  const double step = M_PI / static_cast<double>(n & ~size_t{1});  // 180/181: 1 deg, 360/361: 0.5
  ScanEnds out;
  out.ends.resize(n);
  out.valid.assign(n, 0);
  out.joined.assign(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const double r = scan.ranges[i];
    if (!(r >= o.min_range_m && r < max_range)) {
      ++out.dropped;
      continue;
    }
    const double bearing = -M_PI / 2 + static_cast<double>(i) * step;
    out.ends[i] = T_slam_robot * Eigen::Vector2d(r * std::cos(bearing), r * std::sin(bearing));
    out.valid[i] = 1;
  }
  for (size_t i = 0; i + 1 < n; ++i) {
    const double near = std::min(scan.ranges[i], scan.ranges[i + 1]);
    out.joined[i] =
        out.valid[i] && out.valid[i + 1] &&
        (out.ends[i] - out.ends[i + 1]).norm() <= o.break_m + o.break_beams * step * near;
  }
  return out;
}

// The wall mesh of one scan: a quad from the floor to wall_height_m per joined pair.
sim::SimMesh ScanMesh(const ScanEnds& scan, const CarmenImportOptions& o, uint64_t id) {
  sim::SimMesh mesh;
  mesh.id = id;
  mesh.change = sim::MeshChange::kAdded;
  std::vector<int> vertex(scan.ends.size(), -1);  // bottom vertex of an end point; top is +1
  auto vertex_of = [&](size_t i) {
    if (vertex[i] < 0) {
      vertex[i] = static_cast<int>(mesh.vertices_slam.size());
      const Eigen::Vector2f p = scan.ends[i].cast<float>();
      mesh.vertices_slam.emplace_back(p.x(), p.y(), 0.0f);
      mesh.vertices_slam.emplace_back(p.x(), p.y(), static_cast<float>(o.wall_height_m));
    }
    return static_cast<uint32_t>(vertex[i]);
  };
  for (size_t i = 0; i + 1 < scan.ends.size(); ++i) {
    if (!scan.joined[i]) continue;
    const uint32_t a = vertex_of(i), b = vertex_of(i + 1);
    mesh.triangles.insert(mesh.triangles.end(), {a, b, b + 1, a, b + 1, a + 1});
  }
  return mesh;
}

// An exact wall pick on a scan: the nearest end point (within pick_max_range_m) joined to
// its neighbours on both sides, with the normal of that stretch.
bool ExactPick(const CarmenScan& scan, const ScanEnds& ends, const Se2& T_plan_slam,
               const CarmenImportOptions& o, WallPick* pick) {
  double best = o.pick_max_range_m;
  bool found = false;
  for (size_t i = 1; i + 1 < ends.ends.size(); ++i) {
    if (!ends.joined[i - 1] || !ends.joined[i] || !(scan.ranges[i] < best)) continue;
    const Eigen::Vector2d along = ends.ends[i + 1] - ends.ends[i - 1];
    if (along.norm() < 1e-3) continue;
    pick->slam_point = ends.ends[i];
    pick->slam_normal = Eigen::Vector2d(-along.y(), along.x()).normalized();
    pick->plan_point = T_plan_slam * pick->slam_point;
    pick->plan_normal = T_plan_slam.R() * pick->slam_normal;
    best = scan.ranges[i];
    found = true;
  }
  return found;
}

}  // namespace

bool ParseCarmenLog(std::string_view text, CarmenLog* log, std::string* error) {
  *log = {};
  size_t pos = 0, line_no = 0;
  while (pos < text.size()) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    const std::string_view line = text.substr(pos, eol - pos);
    pos = eol + 1;
    const size_t this_line = line_no++;
    if (line.rfind("FLASER", 0) != 0) {
      if (!Fields(line).empty()) ++log->skipped_lines;
      continue;
    }
    const std::vector<std::string_view> f = Fields(line);
    auto fail = [&](const std::string& why) {
      *error = "line " + std::to_string(this_line + 1) + ": FLASER: " + why;
      return false;
    };
    double count = 0;
    if (f.size() < 2 || !ToDouble(f[1], &count) || count < 2 || count > kMaxBeams ||
        count != std::floor(count))
      return fail("bad beam count");
    const size_t n = static_cast<size_t>(count);
    // n ranges, x y theta, odom x y theta, ipc_timestamp (host and logger stamp optional).
    if (f.size() < 2 + n + 7) return fail("expected " + std::to_string(n) + " ranges and a pose");
    CarmenScan scan;
    scan.line = this_line;
    scan.ranges.resize(n);
    for (size_t i = 0; i < n; ++i) {
      double r = 0;
      if (!ToDouble(f[2 + i], &r) || r < 0) return fail("range " + std::to_string(i) + " invalid");
      scan.ranges[i] = static_cast<float>(r);
      log->max_reading = std::max(log->max_reading, scan.ranges[i]);
    }
    double v[7];
    for (int k = 0; k < 7; ++k)
      if (!ToDouble(f[2 + n + k], &v[k])) return fail("pose or timestamp not a number");
    scan.corrected = {{v[0], v[1]}, WrapAngle(v[2]), 0.0};
    scan.timestamp = v[6];
    log->scans.push_back(std::move(scan));
  }
  log->lines = line_no;
  if (log->scans.size() < 2) {
    *error = "fewer than two FLASER messages";
    return false;
  }
  return true;
}

bool ReadCarmenLog(const std::string& path, CarmenLog* log, std::string* error) {
  // gzread passes uncompressed files through unchanged.
  gzFile in = gzopen(path.c_str(), "rb");
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  std::string text;
  char buffer[1 << 16];
  int got = 0;
  while ((got = gzread(in, buffer, sizeof buffer)) > 0) {
    text.append(buffer, static_cast<size_t>(got));
    if (text.size() > kMaxLogBytes) break;
  }
  int code = Z_OK;
  const char* message = gzerror(in, &code);
  const std::string gz_error = code != Z_OK && code != Z_STREAM_END ? message : "";
  gzclose(in);
  if (got < 0 || !gz_error.empty()) {
    *error = path + ": corrupt gzip data: " + gz_error;
    return false;
  }
  if (text.size() > kMaxLogBytes) {
    *error = path + ": over " + std::to_string(kMaxLogBytes >> 20) + " MB decompressed";
    return false;
  }
  if (!ParseCarmenLog(text, log, error)) {
    *error = path + ": " + *error;
    return false;
  }
  return true;
}

namespace {

// The log's clock, seconds or line numbers (report->line_clock), and the walk's: the scans'
// times in each (a line-numbered log is paced at pace_mps). False: the ground truth is
// not this log's.
bool WalkClock(const CarmenLog& log, const std::vector<sim::TimedPose>& ground_truth,
               const CarmenImportOptions& o, std::vector<double>* clock_out,
               std::vector<double>* walk_out, CarmenImportReport* report, std::string* error) {
  const size_t n = log.scans.size();
  // The log's clock: seconds, or line numbers where the timestamps were unusable.
  bool lines = true, seconds = true;
  for (size_t i = 0; i < n; ++i) {
    lines = lines && ground_truth[i].t_s == static_cast<double>(log.scans[i].line);
    seconds = seconds && std::abs(ground_truth[i].t_s - log.scans[i].timestamp) < 1e-3;
  }
  if (!lines && !seconds) {
    *error =
        "the ground truth's timestamps are neither the scans' timestamps nor their line "
        "numbers: not this log's";
    return false;
  }
  report->line_clock = lines && !seconds;
  // Knots: the scans' times in the log's clock and in seconds of the walk.
  std::vector<double>& clock = *clock_out;
  std::vector<double>& walk = *walk_out;
  clock.assign(n, 0.0);
  walk.assign(n, 0.0);
  for (size_t i = 0; i < n; ++i) clock[i] = ground_truth[i].t_s;
  if (report->line_clock) {
    std::vector<sim::TimedPose> paced = ground_truth;
    PaceTrajectory(&paced, o.pace_mps, o.turn_rad_s);
    for (size_t i = 0; i < n; ++i) walk[i] = paced[i].t_s;
  } else {
    walk = clock;
  }
  return true;
}

// Every pose period of the walk a step: the odometry's pose, the truth blended between the
// scans' corrections, and the scans that came, as meshes; nothing while the odometry is
// silent for more than max_odometry_gap_s.
void WalkSteps(const CarmenLog& log, const Track& odom, const std::vector<double>& clock,
               const std::vector<double>& walk, const std::vector<Se2>& odom_at_scan,
               const std::vector<Se2>& T_plan_slam, double max_range, const CarmenImportOptions& o,
               sim::Simulation* out, CarmenImportReport* report) {
  const size_t n = log.scans.size();
  size_t next_scan = 0;
  bool silent = false;
  const auto steps = static_cast<size_t>(std::ceil((walk.back() - walk.front()) / o.pose_period_s));
  for (size_t k = 0; k <= steps; ++k) {
    const double t_walk = walk.front() + static_cast<double>(k) * o.pose_period_s;
    const double t = report->line_clock ? MapClock(walk, clock, t_walk) : t_walk;
    const double gap = report->line_clock ? 0.0 : odom.Gap(t);
    if (gap > o.max_odometry_gap_s) {  // the motion is unknown: nothing is sent
      report->silent_s += o.pose_period_s;
      if (!silent) ++report->odometry_gaps;
      silent = true;
      for (; next_scan < n && walk[next_scan] <= t_walk + 1e-9; ++next_scan) ++report->silent_scans;
      continue;
    }
    silent = false;
    sim::SimulatedStep step;
    step.stamp_ns = static_cast<int64_t>(std::llround(t_walk * 1e9));
    const Se2 slam = odom.At(t);
    // The truth between scans i-1 and i: the odometry's motion from each, blended.
    const size_t i = std::min<size_t>(
        std::max<size_t>(std::upper_bound(clock.begin(), clock.end(), t) - clock.begin(), 1),
        n - 1);
    const double u = std::clamp((t - clock[i - 1]) / (clock[i] - clock[i - 1]), 0.0, 1.0);
    const Se2 T = Lerp(T_plan_slam[i - 1], T_plan_slam[i], u);
    step.slam = ToPose(slam, o.eye_height_m);
    step.true_plan = ToPose(T * slam, o.eye_height_m);
    step.T_slam_plan = T.Inverse();
    for (; next_scan < n && walk[next_scan] <= t_walk + 1e-9; ++next_scan) {
      const CarmenScan& scan = log.scans[next_scan];
      const ScanEnds ends = EndPoints(scan, odom_at_scan[next_scan], max_range, o);
      report->dropped_readings += ends.dropped;
      step.meshes.push_back(ScanMesh(ends, o, next_scan + 1));
      report->readings += scan.ranges.size();
      report->triangles += step.meshes.back().triangles.size() / 3;
      out->counts.added++;
      out->counts.vertices += step.meshes.back().vertices_slam.size();
      out->counts.triangles += step.meshes.back().triangles.size() / 3;
    }
    out->steps.push_back(std::move(step));
  }
  report->scans = next_scan - report->silent_scans;
}

// The walk's length and time, and how far the odometry alone drifts from the exact start.
void MeasureWalk(const std::vector<sim::TimedPose>& ground_truth,
                 const std::vector<Se2>& odom_at_scan, const std::vector<Se2>& T_plan_slam,
                 const std::vector<double>& walk, CarmenImportReport* report) {
  const size_t n = ground_truth.size();
  for (size_t i = 1; i < n; ++i)
    report->length_m += (ground_truth[i].position - ground_truth[i - 1].position).norm();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d odom_only = T_plan_slam[0] * odom_at_scan[i].t;
    const double e = (odom_only - ground_truth[i].position).norm();
    report->odom_max_error_m = std::max(report->odom_max_error_m, e);
    report->odom_final_error_m = e;
  }
  report->duration_s = walk.back() - walk.front();
}

std::string Describe(const CarmenImportOptions& o, size_t n, double max_range,
                     const CarmenImportReport* report) {
  std::ostringstream d;
  d.precision(3);
  d << o.name << ": " << n << " scans, " << report->triangles << " wall triangles ("
    << report->dropped_readings << " of " << report->readings << " readings dropped: at or over "
    << max_range << " m or under " << o.min_range_m << " m), walls 0.." << o.wall_height_m
    << " m, poses every " << o.pose_period_s << " s";
  if (report->odometry_gaps > 0)
    d << ", odometry silent " << report->odometry_gaps << " time(s) over " << o.max_odometry_gap_s
      << " s (" << report->silent_s << " s, " << report->silent_scans
      << " scans): no pose and no scan then";
  d << (report->line_clock
            ? ", clock: line numbers, paced at " + std::to_string(o.pace_mps) + " m/s"
            : ", clock: seconds");
  return d.str();
}

}  // namespace

bool CarmenToSimulation(const CarmenLog& log, const std::vector<sim::TimedPose>& odometry,
                        const std::vector<sim::TimedPose>& ground_truth,
                        const CarmenImportOptions& o, sim::Simulation* out,
                        CarmenImportReport* report, std::string* error) {
  *out = {};
  *report = {};
  const size_t n = log.scans.size();
  if (ground_truth.size() != n) {
    *error = "the ground truth has " + std::to_string(ground_truth.size()) + " poses for " +
             std::to_string(n) + " scans (one per FLASER, in log order)";
    return false;
  }
  if (odometry.size() < 2) {
    *error = "the odometry needs at least two poses";
    return false;
  }
  std::vector<double> clock, walk;
  if (!WalkClock(log, ground_truth, o, &clock, &walk, report, error)) return false;
  const Track odom(odometry);
  const double max_range = o.max_range_m > 0 ? o.max_range_m : log.max_reading;

  // Per scan: the odometry reading it was paired with, and the correction onto the truth.
  std::vector<Se2> odom_at_scan(n), T_plan_slam(n);
  for (size_t i = 0; i < n; ++i) {
    odom_at_scan[i] = odom.LastAt(clock[i]);
    T_plan_slam[i] = ToSe2(ground_truth[i]) * odom_at_scan[i].Inverse();
  }
  out->T_slam_plan_initial = T_plan_slam[0].Inverse();

  WalkSteps(log, odom, clock, walk, odom_at_scan, T_plan_slam, max_range, o, out, report);
  if (!ExactPick(log.scans[0], EndPoints(log.scans[0], odom_at_scan[0], max_range, o),
                 T_plan_slam[0], o, &out->pick)) {
    *error =
        "the first scan has no wall within " + std::to_string(o.pick_max_range_m) + " m to pick";
    return false;
  }
  out->pick_step = 0;
  out->pick_height_m = 1.3;
  out->pick_error = Se2::Identity();

  MeasureWalk(ground_truth, odom_at_scan, T_plan_slam, walk, report);
  out->length_m = report->length_m;
  out->duration_s = report->duration_s;
  out->description = Describe(o, n, max_range, report);
  return true;
}

}  // namespace floorpose::tools
