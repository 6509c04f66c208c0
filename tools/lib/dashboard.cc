#include "tools/lib/dashboard.h"

#include <httplib.h>
#include <png.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <stdexcept>

#include "core/rooms.h"
#include "platform/clock.h"
#include "platform/dds.h"
#include "platform/explored_codec.h"
#include "platform/floor_plan_io.h"

namespace floorpose::tools {

// The page, its script and style, compiled in from tools/dashboard/ (dashboard_assets.cc,
// made by CMake): served by the tool itself, so the dashboard works with no network.
struct DashboardAsset {
  const char* path;
  const char* content_type;
  const char* body;
};
extern const DashboardAsset kDashboardAssets[];

namespace {

using json = nlohmann::json;
using Clock = DashboardState::Clock;
using platform::Topic;

double Mm(double v) { return std::round(v * 1000.0) / 1000.0; }

// The reliability classes the page colours by.
const char* FlagClass(int flag) {
  switch (flag) {
    case v1::Reliability::RELIABLE: return "reliable";
    case v1::Reliability::DEGRADED: return "degraded";
    default: return "lost";
  }
}

bool Finite(const v1::PlanPose& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.heading());
}

}  // namespace

DashboardState::Device* DashboardState::Touch(const std::string& device, Clock::time_point now) {
  auto it = devices_.find(device);
  if (it == devices_.end()) {
    if (devices_.size() >= options_.max_devices) {
      if (refused_devices_++ % 1000 == 0)
        spdlog::warn("{} devices already shown: ignoring device '{}' ({} messages ignored so far)",
                     devices_.size(), device, refused_devices_);
      return nullptr;
    }
    it = devices_.emplace(device, Device{}).first;
  }
  Device& d = it->second;
  d.last_message = now;
  d.version = ++version_;
  return &d;
}

void DashboardState::Append(Device& d, const v1::PlanPose& p) {
  if (!d.trail.empty() && p.source_stamp_ns() <= d.trail.back().stamp_ns) return;
  d.trail.push_back({p.x(), p.y(), p.reliability().flag(), p.source_stamp_ns()});
  while (d.trail.size() > options_.trail_points) {
    d.trail.pop_front();
    ++d.trail_first_seq;
  }
}

void DashboardState::OnPlanPose(const std::string& device, const v1::PlanPose& pose,
                                Clock::time_point now) {
  if (!Finite(pose)) return;
  {
    std::lock_guard lock(mu_);
    Device* found = Touch(device, now);
    if (!found) return;
    Device& d = *found;
    d.last_pose = now;
    // A late pose (older than the one shown) is history, not where the wearer is; one far
    // older is from a headset whose clock started again.
    const auto gap = static_cast<int64_t>(options_.restart_gap_s * 1e9);
    if (d.pose && pose.source_stamp_ns() < d.pose->source_stamp_ns() - gap) {
      d.trail.clear();
      ++d.trail_epoch;
      d.trail_first_seq = 0;
      d.pose.reset();
    }
    if (!d.pose || pose.source_stamp_ns() >= d.pose->source_stamp_ns()) d.pose = pose;
    Append(d, pose);
  }
  changed_.notify_all();
}

void DashboardState::OnPlanTrack(const std::string& device, const v1::PlanTrack& track,
                                 Clock::time_point now) {
  {
    std::lock_guard lock(mu_);
    Device* found = Touch(device, now);
    if (!found) return;
    Device& d = *found;
    // The daemon re-projected its recent track with a new alignment: it replaces ours,
    // keeping the poses that came after it.
    std::deque<TrailPoint> newer;
    const int64_t last =
        track.poses_size() ? track.poses(track.poses_size() - 1).source_stamp_ns() : INT64_MIN;
    for (const TrailPoint& t : d.trail)
      if (t.stamp_ns > last) newer.push_back(t);
    d.trail.clear();
    for (const v1::PlanPose& p : track.poses())
      if (Finite(p)) Append(d, p);
    for (const TrailPoint& t : newer) d.trail.push_back(t);
    while (d.trail.size() > options_.trail_points) d.trail.pop_front();
    ++d.trail_epoch;
    d.trail_first_seq = 0;
  }
  changed_.notify_all();
}

void DashboardState::OnAlignment(const std::string& device, const v1::Alignment& alignment,
                                 Clock::time_point now) {
  {
    std::lock_guard lock(mu_);
    if (Device* d = Touch(device, now)) d->alignment = alignment;
  }
  changed_.notify_all();
}

void DashboardState::OnStatus(const std::string& device, const v1::DaemonStatus& status,
                              Clock::time_point now) {
  {
    std::lock_guard lock(mu_);
    if (Device* d = Touch(device, now)) {
      d->status = status;
      d->alert = status.alert();
    }
  }
  changed_.notify_all();
}

void DashboardState::OnAlert(const std::string& device, const v1::Alert& alert,
                             Clock::time_point now) {
  {
    std::lock_guard lock(mu_);
    if (Device* d = Touch(device, now)) d->alert = alert;
  }
  changed_.notify_all();
}

bool DashboardState::OnMarker(const v1::Marker& marker, std::string* why) {
  bool changed = false;
  {
    std::lock_guard lock(mu_);
    const platform::MarkerBoard::Take take = markers_.Merge(marker, why);
    changed =
        take == platform::MarkerBoard::Take::kNew || take == platform::MarkerBoard::Take::kReplaced;
    if (changed) ++version_;
    if (take == platform::MarkerBoard::Take::kRefused) return false;
  }
  if (changed) changed_.notify_all();
  return changed;
}

std::optional<v1::Marker> DashboardState::MarkerById(const std::string& id) const {
  std::lock_guard lock(mu_);
  auto it = markers_.markers().find(id);
  if (it == markers_.markers().end()) return std::nullopt;
  return it->second;
}

void DashboardState::SaveMarkers(const std::string& path) {
  if (path.empty()) return;
  std::lock_guard lock(mu_);
  if (markers_.revision() == saved_markers_) return;
  std::string error;
  if (!markers_.Save(path, &error)) spdlog::warn("markers not saved to {}: {}", path, error);
  saved_markers_ = markers_.revision();
}

bool DashboardState::OnExplored(const std::string& device, const v1::ExploredMap& map,
                                Clock::time_point now, std::string* error) {
  std::vector<int8_t> cells;
  *error = platform::UnpackExploredCells(map, &cells);
  if (!error->empty()) return false;
  if (!std::isfinite(map.origin_x()) || !std::isfinite(map.origin_y()) || !(map.cell_m() > 0) ||
      !std::isfinite(map.cell_m())) {
    *error = "explored map with a non-finite origin or cell size";
    return false;
  }
  {
    std::lock_guard lock(mu_);
    Device* d = Touch(device, now);
    if (!d) return true;
    d->explored = map;
    d->explored->clear_log_odds_zlib();
    d->explored_cells = std::move(cells);
    ++explored_version_;
  }
  changed_.notify_all();
  return true;
}

std::vector<const DashboardState::Device*> DashboardState::ExploredOf(
    const std::string& plan_id) const {
  std::vector<const Device*> out;
  for (const auto& [id, d] : devices_) {
    if (!d.explored || d.explored->plan_id() != plan_id) continue;
    const v1::ExploredMap& first = out.empty() ? *d.explored : *out.front()->explored;
    if (d.explored->width() == first.width() && d.explored->height() == first.height() &&
        std::abs(d.explored->cell_m() - first.cell_m()) < 1e-9 &&
        std::abs(d.explored->origin_x() - first.origin_x()) < 1e-6 &&
        std::abs(d.explored->origin_y() - first.origin_y()) < 1e-6)
      out.push_back(&d);
  }
  return out;
}

std::string DashboardState::ExploredPng(const std::string& plan_id) const {
  std::lock_guard lock(mu_);
  auto cached = png_cache_.find(plan_id);
  if (cached != png_cache_.end() && cached->second.first == explored_version_)
    return cached->second.second;
  const std::vector<const Device*> maps = ExploredOf(plan_id);
  if (maps.empty()) return {};
  const v1::ExploredMap& g = *maps.front()->explored;
  const size_t n = maps.front()->explored_cells.size();
  std::vector<int> sum(n, 0);
  for (const Device* d : maps)
    for (size_t i = 0; i < n; ++i) sum[i] += d->explored_cells[i];
  // RGBA, rows as the grid has them (from origin_y upwards): written bottom-up below.
  std::vector<unsigned char> rgba(n * 4, 0);
  for (size_t i = 0; i < n; ++i) {
    if (sum[i] == 0) continue;
    const double strength = std::min(1.0, std::abs(sum[i]) / 64.0);
    unsigned char* px = &rgba[i * 4];
    if (sum[i] < 0) {  // free: seen through
      px[0] = 66, px[1] = 133, px[2] = 244;
      px[3] = static_cast<unsigned char>(20 + 60 * strength);
    } else {  // a wall the headset saw
      px[0] = 25, px[1] = 70, px[2] = 160;
      px[3] = static_cast<unsigned char>(60 + 120 * strength);
    }
  }
  const std::string png = EncodePngBottomUp(g.width(), g.height(), rgba);
  if (png.empty()) spdlog::warn("explored map of plan '{}' not encoded", plan_id);
  png_cache_[plan_id] = {explored_version_, png};
  return png;
}

std::string EncodePngBottomUp(uint32_t width, uint32_t height,
                              const std::vector<unsigned char>& rgba) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = width;
  image.height = height;
  image.format = PNG_FORMAT_RGBA;
  const auto stride = -static_cast<png_int_32>(width * 4);  // bottom-up: north up
  png_alloc_size_t size = 0;
  std::string png;
  if (png_image_write_to_memory(&image, nullptr, &size, 0, rgba.data(), stride, nullptr)) {
    png.resize(size);
    if (!png_image_write_to_memory(&image, png.data(), &size, 0, rgba.data(), stride, nullptr))
      png.clear();
    png.resize(size);
  }
  return png;
}

std::vector<Eigen::Vector2d> DashboardState::SearchedOn(const std::string& plan_id) const {
  std::lock_guard lock(mu_);
  std::vector<Eigen::Vector2d> out;
  for (const auto& [id, m] : markers_.markers())
    if (!m.removed() && m.kind() == v1::Marker::SEARCHED && m.plan_id() == plan_id)
      out.emplace_back(m.x(), m.y());
  return out;
}

json DashboardState::DeviceJson(const std::string& id, const Device& d) const {
  json dev = {{"id", id}};
  const auto name = options_.names.find(id);
  dev["name"] = name == options_.names.end() ? id : name->second;
  dev["plan"] = d.status ? d.status->plan_id() : "";
  dev["state"] = d.status ? v1::DaemonStatus::State_Name(d.status->state()) : "";
  if (d.status && !d.status->message().empty()) dev["message"] = d.status->message();
  if (d.pose) {
    const v1::PlanPose& p = *d.pose;
    dev["pose"] = {{"x", Mm(p.x())},
                   {"y", Mm(p.y())},
                   {"heading", std::round(p.heading() * 1e4) / 1e4},
                   {"floor", p.floor()},
                   {"flag", FlagClass(p.reliability().flag())},
                   {"probability", std::round(p.reliability().probability() * 1e3) / 1e3},
                   {"reason", p.reliability().reason()},
                   {"alignment_version", p.alignment_version()},
                   {"stamp_ns", p.source_stamp_ns()}};
  }
  if (d.alert && d.alert->kind() != v1::Alert::NONE)
    dev["alert"] = {{"kind", d.alert->kind() == v1::Alert::NO_MOTION ? "no_motion" : "pre_alert"},
                    {"still_s", std::round(d.alert->still_s() * 10.0) / 10.0},
                    {"acknowledged", d.alert->acknowledged()},
                    {"by", d.alert->acknowledged_by()}};
  if (d.alignment)
    dev["alignment"] = {{"version", d.alignment->version()},
                        {"source", v1::Alignment::Source_Name(d.alignment->source())},
                        {"rmse_m", Mm(d.alignment->stats().inlier_rmse_m())}};
  return dev;
}

json DashboardState::TrailJson(const std::string& id, const Device& d, Cursor* cursor) const {
  // The trail points this browser lacks; all of them after a re-projection.
  auto [epoch, next] = cursor->trails[id];
  const bool reset = epoch != d.trail_epoch || next < d.trail_first_seq;
  const uint64_t from = reset ? d.trail_first_seq : next;
  json points = json::array();
  for (uint64_t s = from; s < d.trail_first_seq + d.trail.size(); ++s) {
    const TrailPoint& t = d.trail[s - d.trail_first_seq];
    points.push_back({Mm(t.x), Mm(t.y), FlagClass(t.flag)});
  }
  cursor->trails[id] = {d.trail_epoch, d.trail_first_seq + d.trail.size()};
  if (!reset && points.empty()) return nullptr;
  return {{"reset", reset}, {"points", std::move(points)}};
}

json DashboardState::ExploredJson() const {
  std::set<std::string> plans;
  for (const auto& [id, d] : devices_)
    if (d.explored) plans.insert(d.explored->plan_id());
  json explored = json::object();
  for (const std::string& plan : plans) {
    const std::vector<const Device*> maps = ExploredOf(plan);
    const v1::ExploredMap& g = *maps.front()->explored;
    std::map<uint32_t, const v1::ExploredMap::Room*> visited;  // the union, by room id
    for (const Device* d : maps)
      for (const auto& r : d->explored->visited()) visited.emplace(r.id(), &r);
    json rooms = json::array();
    for (const auto& [id, r] : visited) rooms.push_back({Mm(r->x()), Mm(r->y())});
    explored[plan] = {
        {"version", explored_version_}, {"origin", {Mm(g.origin_x()), Mm(g.origin_y())}},
        {"cell_m", g.cell_m()},         {"width", g.width()},
        {"height", g.height()},         {"devices", maps.size()},
        {"rooms", g.rooms()},           {"visited", std::move(rooms)}};
  }
  return explored;
}

json DashboardState::MarkersJson() const {
  // Every marker, removed ones as such: few, and the page replaces its set.
  json list = json::array();
  for (const auto& [id, m] : markers_.markers())
    list.push_back({{"id", id},
                    {"kind", platform::MarkerKindName(m.kind())},
                    {"plan", m.plan_id()},
                    {"floor", m.floor()},
                    {"x", Mm(m.x())},
                    {"y", Mm(m.y())},
                    {"radius_m", Mm(m.radius_m())},
                    {"text", m.text()},
                    {"author", m.author()},
                    {"removed", m.removed()}});
  return list;
}

std::string DashboardState::Frame(Cursor* cursor, Clock::time_point now) const {
  std::lock_guard lock(mu_);
  json frame = {{"stale_after_s", options_.stale_after_s}};
  json& out = frame["devices"] = json::array();
  json& ages = frame["ages"] = json::object();
  json& stale = frame["stale"] = json::array();
  for (const auto& [id, d] : devices_) {
    const double age =
        std::chrono::duration<double>(now - (d.pose ? d.last_pose : d.last_message)).count();
    ages[id] = std::round(age * 10.0) / 10.0;
    if (age > options_.stale_after_s) stale.push_back(id);
    if (d.version <= cursor->version) continue;
    json dev = DeviceJson(id, d);
    if (json trail = TrailJson(id, d, cursor); !trail.is_null()) dev["trail"] = std::move(trail);
    out.push_back(std::move(dev));
  }
  if (cursor->explored_version < explored_version_) {
    frame["explored"] = ExploredJson();
    cursor->explored_version = explored_version_;
  }
  if (cursor->markers_revision != markers_.revision()) {
    frame["markers"] = MarkersJson();
    cursor->markers_revision = markers_.revision();
  }
  cursor->version = version_;
  // Device ids and reasons come off the network: invalid UTF-8 is replaced, not thrown.
  return frame.dump(-1, ' ', false, json::error_handler_t::replace);
}

void DashboardState::WaitForChange(uint64_t version, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mu_);
  changed_.wait_for(lock, timeout, [&] { return version_ > version || stopped_; });
}

void DashboardState::Stop() {
  {
    std::lock_guard lock(mu_);
    stopped_ = true;
  }
  changed_.notify_all();
}

size_t DashboardState::devices() const {
  std::lock_guard lock(mu_);
  return devices_.size();
}

namespace {

// A plan file, or every floor of a .floors set; false (logged) when it does not load.
bool LoadDrawn(const std::string& path, std::vector<DashboardPlan>* plans) {
  if (!platform::IsFloorSet(path)) {
    FloorPlanParse parse = platform::LoadFloorPlan(path);
    if (!parse.ok()) {
      spdlog::error("{}: {}", path, parse.error);
      return false;
    }
    spdlog::info("plan '{}': {} walls from {}{}", parse.plan.id, parse.plan.segments.size(), path,
                 parse.georeference ? ", georeferenced" : "");
    plans->push_back({std::move(parse.plan), "", "", 0.0, parse.georeference});
    return true;
  }
  const platform::FloorSet set = platform::LoadFloorSet(path);
  if (!set.ok()) {
    spdlog::error("{}", set.error);
    return false;
  }
  const std::string name = std::filesystem::path(path).stem().string();
  std::vector<DashboardPlan> floors;
  std::optional<Georeference> shared;
  for (const platform::FloorEntry& f : set.floors) {
    FloorPlanParse parse = platform::LoadFloorPlan(f.plan_path);
    if (!parse.ok()) {
      spdlog::error("{}: floor {}: {}", path, f.id, parse.error);
      return false;
    }
    if (!shared) shared = parse.georeference;
    floors.push_back({std::move(parse.plan), name, f.id, f.height_m, parse.georeference});
  }
  for (DashboardPlan& f : floors)
    if (!f.georeference) f.georeference = shared;  // one building, one frame
  spdlog::info("plan set '{}': {} floors from {}{}", name, floors.size(), path,
               shared ? ", georeferenced" : "");
  for (DashboardPlan& f : floors) plans->push_back(std::move(f));
  return true;
}

}  // namespace

bool LoadDashboardPlans(const std::string& plan, const std::string& plans_dir,
                        std::vector<DashboardPlan>* plans) {
  std::vector<std::string> paths;
  if (!plan.empty()) paths.push_back(plan);
  if (!plans_dir.empty()) {
    const std::vector<std::string> ids = platform::ListPlanIds(plans_dir);
    if (ids.empty()) {
      spdlog::error("--plans {}: no floor plans there", plans_dir);
      return false;
    }
    for (const std::string& id : ids) {
      std::string path, error;
      if (platform::FindPlanFile(plans_dir, id, &path, &error)) paths.push_back(path);
    }
  }
  for (const std::string& path : paths)
    if (!LoadDrawn(path, plans) && path == plan) return false;  // the one plan asked for
  // (one bad file of a directory: the others still show)
  if (plans->empty())
    spdlog::warn("no floor plan: wearers are listed, not placed (give --plan or --plans)");
  return true;
}

std::vector<CotPlan> CotPlansOf(const std::vector<DashboardPlan>& plans) {
  std::vector<CotPlan> out;
  for (const DashboardPlan& p : plans)
    if (p.georeference) out.push_back({p.plan.id, *p.georeference, p.height_m});
  return out;
}

std::string PlansJson(const std::vector<DashboardPlan>& plans,
                      const std::map<std::string, std::unique_ptr<RoomMap>>& rooms) {
  json out = {{"plans", json::array()}};
  for (const DashboardPlan& drawn : plans) {
    const FloorPlan& plan = drawn.plan;
    // Walls as [x1, y1, x2, y2]; every other line (windows, glass, stairs, elevators,
    // doors, exits) by kind, each drawn its own way.
    json walls = json::array(), lines = json::object();
    auto coords = [](const Segment& s) {
      return json::array({Mm(s.a.x()), Mm(s.a.y()), Mm(s.b.x()), Mm(s.b.y())});
    };
    for (size_t i = 0; i < plan.segments.size(); ++i) {
      const LineKind kind = plan.KindOf(i);
      if (kind == LineKind::kWall)
        walls.push_back(coords(plan.segments[i]));
      else
        lines[LineKindName(kind)].push_back(coords(plan.segments[i]));
    }
    for (const PlanLine& o : plan.openings)
      lines[LineKindName(o.kind)].push_back(coords(o.segment));
    out["plans"].push_back({{"id", plan.id},
                            {"min", {Mm(plan.min.x()), Mm(plan.min.y())}},
                            {"max", {Mm(plan.max.x()), Mm(plan.max.y())}},
                            {"walls", std::move(walls)},
                            {"lines", std::move(lines)},
                            {"set", drawn.set},
                            {"floor", drawn.floor}});
    if (auto r = rooms.find(plan.id); r != rooms.end()) {
      const GridGeometry& g = r->second->grid();
      out["plans"].back()["rooms_grid"] = {{"origin", {Mm(g.origin.x()), Mm(g.origin.y())}},
                                           {"cell_m", g.cell_m},
                                           {"width", g.nx},
                                           {"height", g.ny}};
    }
    // North on the plan, counter-clockwise from its +x, when the plan says where it lies.
    if (drawn.georeference)
      out["plans"].back()["north_rad"] =
          std::round((M_PI / 2 - drawn.georeference->rotation_rad) * 1e4) / 1e4;
  }
  return out.dump(-1, ' ', false, json::error_handler_t::replace);
}

struct Dashboard::Impl {
  DashboardServerOptions options;
  std::string plans_json;
  std::unique_ptr<platform::Participant> participant;
  std::vector<std::unique_ptr<platform::Reader>> readers;
  std::unique_ptr<platform::Waiter> waiter;
  std::thread dds_thread;
  std::atomic<bool> stop{false};
  httplib::Server http;
  std::atomic<int> clients{0};
  // Markers placed here and re-published, and the leads' acknowledgements (commands to a
  // device's daemon). Written from the DDS thread and the HTTP threads.
  std::mutex write_mu;
  std::unique_ptr<platform::Writer> marker_writer, command_writer;
  uint64_t next_request_id = 1;
  std::atomic<uint64_t> placed{0};  // markers placed here, for their ids
  // Replies to this dashboard's commands, by device and request id, until taken.
  std::mutex reply_mu;
  std::condition_variable reply_cv;
  std::map<std::pair<std::string, uint64_t>, std::optional<v1::CommandReply>> replies;
  std::unique_ptr<CotBridge> cot;  // DDS thread only
  // Each plan's rooms, to draw a room searched as searched (GET /api/searched/PLAN.png).
  std::map<std::string, std::unique_ptr<RoomMap>> rooms;

  void ReadDds(DashboardState& state);
  void PublishMarker(const v1::Marker& marker);
  // Returns the request id.
  uint64_t SendCommand(const std::string& device, v1::Command command);
  // Sends and waits for the reply; none after the timeout.
  std::optional<v1::CommandReply> Ask(const std::string& device, v1::Command command,
                                      std::chrono::milliseconds timeout);
  void OnReply(const std::string& device, const v1::CommandReply& reply);

  // The participant, the wearers' readers and, where granted, the lead's topics.
  void JoinDds();
  // The markers saved at options.markers_path, into the state and out on DDS.
  void LoadMarkers(DashboardState& state);
  // GET: the page's files, the plans, the explored and searched maps, the devices.
  void ServeReads(DashboardState& state);
  // GET /events: server-sent frames of the state.
  void ServeEvents(DashboardState& state);
  // POST: markers, alert acknowledgements and routes asked of a wearer's daemon.
  void ServeLead(DashboardState& state);
  void PostMarker(DashboardState& state, const httplib::Request& req, httplib::Response& res);
  void PostRoute(const httplib::Request& req, httplib::Response& res);
  // Binds options.host:port (any free port for 0); the port, or -1.
  int Bind();
};

std::optional<v1::CommandReply> Dashboard::Impl::Ask(const std::string& device, v1::Command command,
                                                     std::chrono::milliseconds timeout) {
  std::unique_lock lock(reply_mu);
  const uint64_t id = next_request_id++;
  command.set_request_id(id);
  const auto key = std::make_pair(device, id);
  replies[key];
  lock.unlock();
  SendCommand(device, command);
  lock.lock();
  reply_cv.wait_for(lock, timeout, [&] { return replies[key].has_value() || stop; });
  std::optional<v1::CommandReply> reply = std::move(replies[key]);
  replies.erase(key);
  return reply;
}

void Dashboard::Impl::OnReply(const std::string& device, const v1::CommandReply& reply) {
  {
    std::lock_guard lock(reply_mu);
    auto it = replies.find({device, reply.request_id()});
    if (it == replies.end()) return;  // another app's, or given up
    it->second = reply;
  }
  reply_cv.notify_all();
}

void Dashboard::Impl::PublishMarker(const v1::Marker& marker) {
  std::lock_guard lock(write_mu);
  if (!marker_writer) return;
  std::string error;  // keyed by the marker's id, the instance key of the marker topic
  if (!marker_writer->WriteMessage(marker.id(), marker, platform::WallClockNs(), &error))
    spdlog::warn("marker {} not published: {}", marker.id(), error);
}

uint64_t Dashboard::Impl::SendCommand(const std::string& device, v1::Command command) {
  if (command.request_id() == 0) {
    std::lock_guard lock(reply_mu);
    command.set_request_id(next_request_id++);
  }
  std::lock_guard lock(write_mu);
  if (!command_writer) return command.request_id();
  std::string error;
  if (!command_writer->WriteMessage(device, command, platform::WallClockNs(), &error))
    spdlog::warn("command to {} not sent: {}", device, error);
  return command.request_id();
}

void Dashboard::Impl::ReadDds(DashboardState& state) {
  size_t malformed = 0;
  auto last_warning = Clock::now() - std::chrono::seconds(10);
  while (!stop) {
    waiter->Wait(std::chrono::milliseconds(200));
    for (auto& reader : readers) {
      for (const platform::Envelope& e : reader->Take(256)) {
        const auto now = Clock::now();
        bool ok = false;
        std::string why = "not the topic's message";
        switch (reader->topic()) {
          case Topic::kPlanPose: {
            v1::PlanPose m;
            if ((ok = m.ParseFromString(e.payload))) state.OnPlanPose(e.device_id, m, now);
            if (ok && cot) cot->OnPlanPose(e.device_id, m);
            break;
          }
          case Topic::kPlanTrack: {
            v1::PlanTrack m;
            if ((ok = m.ParseFromString(e.payload))) state.OnPlanTrack(e.device_id, m, now);
            break;
          }
          case Topic::kAlignment: {
            v1::Alignment m;
            if ((ok = m.ParseFromString(e.payload))) state.OnAlignment(e.device_id, m, now);
            break;
          }
          case Topic::kStatus: {
            v1::DaemonStatus m;
            if ((ok = m.ParseFromString(e.payload))) state.OnStatus(e.device_id, m, now);
            if (ok && cot) cot->OnStatus(e.device_id, m);
            break;
          }
          case Topic::kExplored: {
            v1::ExploredMap m;
            ok = m.ParseFromString(e.payload) && state.OnExplored(e.device_id, m, now, &why);
            break;
          }
          case Topic::kCommandReply: {
            v1::CommandReply m;
            if ((ok = m.ParseFromString(e.payload))) OnReply(e.device_id, m);
            break;
          }
          case Topic::kAlert: {
            v1::Alert m;
            if ((ok = m.ParseFromString(e.payload))) state.OnAlert(e.device_id, m, now);
            break;
          }
          case Topic::kMarker: {
            v1::Marker m;
            ok = m.ParseFromString(e.payload);
            why.clear();
            if (ok && state.OnMarker(m, &why)) {
              PublishMarker(m);  // held for later joiners
              if (cot) cot->OnMarker(m);
            }
            ok = ok && why.empty();
            break;
          }
          default: ok = true;
        }
        if (!ok) {
          if (why.empty()) why = "not the topic's message";
          ++malformed;
          if (now - last_warning > std::chrono::seconds(1)) {
            spdlog::warn("{} bad message(s) so far; the latest on {} from device '{}': {}",
                         malformed, platform::TopicName(reader->topic()), e.device_id, why);
            last_warning = now;
          }
        }
      }
    }
    state.SaveMarkers(options.markers_path);
  }
}

namespace {

// The plan's rooms that hold a SEARCHED marker, green, one pixel a cell of its room grid;
// empty when none does.
std::string SearchedRoomsPng(const RoomMap& map, const std::vector<Eigen::Vector2d>& markers) {
  std::vector<int> searched;
  for (const Eigen::Vector2d& p : markers)
    if (const int room = map.RoomAt(p); room >= 0) searched.push_back(room);
  if (searched.empty()) return {};
  const GridGeometry& g = map.grid();
  std::vector<unsigned char> rgba(g.size() * 4, 0);
  for (int cell = 0; cell < static_cast<int>(g.size()); ++cell) {
    const int room = map.RoomAt(g.CellCentre(cell));
    if (room < 0 || std::find(searched.begin(), searched.end(), room) == searched.end()) continue;
    unsigned char* px = &rgba[static_cast<size_t>(cell) * 4];
    px[0] = 0, px[1] = 158, px[2] = 115, px[3] = 70;  // Okabe-Ito green
  }
  return EncodePngBottomUp(static_cast<uint32_t>(g.nx), static_cast<uint32_t>(g.ny), rgba);
}

// A map drawn fresh each time, or 404 with why there is none.
void SendPng(httplib::Response& res, const std::string& png, const char* missing) {
  if (png.empty()) {
    res.status = 404;
    res.set_content(std::string(missing) + "\n", "text/plain");
    return;
  }
  res.set_header("Cache-Control", "no-cache");
  res.set_content(png, "image/png");
}

void Refuse(httplib::Response& res, int status, const std::string& why) {
  res.status = status;
  res.set_content(json{{"error", why}}.dump(), "application/json");
}

}  // namespace

void Dashboard::Impl::JoinDds() {
  participant = std::make_unique<platform::Participant>(
      options.domain_id, options.cyclone_config, options.security ? &*options.security : nullptr);
  waiter = std::make_unique<platform::Waiter>(*participant);
  for (Topic t :
       {Topic::kStatus, Topic::kAlignment, Topic::kPlanTrack, Topic::kPlanPose, Topic::kExplored}) {
    readers.push_back(std::make_unique<platform::Reader>(*participant, t));
    waiter->Attach(*readers.back());
  }
  try {
    // The lead's part. On a secured domain whose permissions predate these topics the
    // dashboard still shows the wearers.
    std::vector<std::unique_ptr<platform::Reader>> team;
    for (Topic t : {Topic::kAlert, Topic::kMarker, Topic::kCommandReply})
      team.push_back(std::make_unique<platform::Reader>(*participant, t));
    marker_writer = std::make_unique<platform::Writer>(*participant, Topic::kMarker);
    command_writer = std::make_unique<platform::Writer>(*participant, Topic::kCommand);
    for (auto& reader : team) {
      waiter->Attach(*reader);
      readers.push_back(std::move(reader));
    }
  } catch (const std::exception& e) {
    spdlog::warn("DDS: {}: no alerts, markers or routes on this domain (not granted)", e.what());
    marker_writer.reset();
    command_writer.reset();
  }
}

void Dashboard::Impl::LoadMarkers(DashboardState& state) {
  if (options.markers_path.empty()) return;
  platform::MarkerBoard saved;
  std::string error;
  if (!saved.Load(options.markers_path, &error))
    spdlog::warn("markers {} not read: {}", options.markers_path, error);
  for (const auto& [id, marker] : saved.markers()) {
    std::string why;
    state.OnMarker(marker, &why);
    PublishMarker(marker);
  }
  if (!saved.markers().empty())
    spdlog::info("{} markers from {}", saved.markers().size(), options.markers_path);
}

void Dashboard::Impl::ServeReads(DashboardState& state) {
  for (const DashboardAsset* a = kDashboardAssets; a->path; ++a) {
    const DashboardAsset asset = *a;
    http.Get(asset.path, [asset](const httplib::Request&, httplib::Response& res) {
      res.set_content(asset.body, asset.content_type);
    });
  }
  http.Get("/api/plans", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(plans_json, "application/json");
  });
  http.Get(R"(/api/explored/([^/]+)\.png)",
           [&state](const httplib::Request& req, httplib::Response& res) {
             SendPng(res, state.ExploredPng(req.matches[1]), "no explored map of that plan yet");
           });
  http.Get(R"(/api/searched/([^/]+)\.png)", [this, &state](const httplib::Request& req,
                                                           httplib::Response& res) {
    auto map = rooms.find(req.matches[1]);
    const std::string png = map == rooms.end()
                                ? std::string()
                                : SearchedRoomsPng(*map->second, state.SearchedOn(req.matches[1]));
    SendPng(res, png, "no room of that plan searched yet");
  });
  http.Get("/api/devices", [&state](const httplib::Request&, httplib::Response& res) {
    DashboardState::Cursor fresh;
    res.set_content(state.Frame(&fresh, Clock::now()), "application/json");
  });
}

void Dashboard::Impl::ServeEvents(DashboardState& state) {
  // The whole picture first, then what changed, at most every frame_period_s, and at
  // least every second (ages and staleness move on their own).
  http.Get("/events", [this, &state](const httplib::Request& req, httplib::Response& res) {
    struct Stream {
      DashboardState::Cursor cursor;
      bool started = false;
    };
    auto stream = std::make_shared<Stream>();
    const auto period = std::chrono::duration_cast<std::chrono::milliseconds>(
        std::chrono::duration<double>(options.dashboard.frame_period_s));
    spdlog::info("browser {} connected ({} open)", req.remote_addr, ++clients);
    res.set_header("Cache-Control", "no-cache");
    res.set_header("X-Accel-Buffering", "no");
    res.set_chunked_content_provider(
        "text/event-stream",
        [&state, stream, period](size_t, httplib::DataSink& sink) {
          if (stream->started) {
            std::this_thread::sleep_for(period);
            state.WaitForChange(stream->cursor.version, std::chrono::seconds(1));
          }
          stream->started = true;
          if (state.stopped()) {
            sink.done();
            return true;
          }
          const std::string event = "data: " + state.Frame(&stream->cursor, Clock::now()) + "\n\n";
          return sink.write(event.data(), event.size());
        },
        [this, remote = req.remote_addr](bool) {
          spdlog::info("browser {} disconnected ({} open)", remote, --clients);
        });
  });
}

// A marker placed or removed by the lead: {"kind", "plan", "floor", "x", "y", "text",
// "radius_m"}, or {"id", "removed": true}.
void Dashboard::Impl::PostMarker(DashboardState& state, const httplib::Request& req,
                                 httplib::Response& res) {
  const json body = json::parse(req.body, nullptr, false);
  if (!body.is_object()) return Refuse(res, 400, "not a JSON object");
  v1::Marker marker;
  const int64_t now = platform::WallClockNs();
  if (body.value("removed", false)) {
    const std::optional<v1::Marker> held = state.MarkerById(body.value("id", ""));
    if (!held) return Refuse(res, 400, "no such marker");
    marker = *held;
    marker.set_removed(true);
    marker.set_revision(held->revision() + 1);
  } else {
    v1::Marker::Kind kind{};
    if (!platform::ParseMarkerKind(body.value("kind", ""), &kind))
      return Refuse(res, 400, "kind must be hazard, victim, searched, blocked or note");
    if (!body.contains("x") || !body.contains("y") || !body["x"].is_number() ||
        !body["y"].is_number())
      return Refuse(res, 400, "x and y (plan metres) are needed");
    marker.set_id(options.name + "-" + std::to_string(now / 1'000'000) + "-" +
                  std::to_string(++placed));
    marker.set_kind(kind);
    marker.set_plan_id(body.value("plan", ""));
    marker.set_floor(body.value("floor", ""));
    marker.set_x(body["x"].get<double>());
    marker.set_y(body["y"].get<double>());
    marker.set_radius_m(body.value("radius_m", 0.0));
    marker.set_text(body.value("text", ""));
    marker.set_author(options.name);
    marker.set_revision(1);
  }
  marker.set_created_unix_ns(now);
  std::string why;
  if (!state.OnMarker(marker, &why)) return Refuse(res, 400, why.empty() ? "not newer" : why);
  PublishMarker(marker);
  state.SaveMarkers(options.markers_path);
  res.set_content(json{{"id", marker.id()}}.dump(), "application/json");
}

// A wearer's way out or way back, asked of its daemon: {"device", "to": "exit" or
// "backtrack"}; the reply's path, or why there is none.
void Dashboard::Impl::PostRoute(const httplib::Request& req, httplib::Response& res) {
  const json body = json::parse(req.body, nullptr, false);
  const std::string device = body.is_object() ? body.value("device", "") : "";
  const std::string to = body.is_object() ? body.value("to", "") : "";
  if (device.empty() || device.size() > 128 || (to != "exit" && to != "backtrack"))
    return Refuse(res, 400, "device and to (exit or backtrack) are needed");
  v1::Command route;
  route.mutable_route()->set_destination(to == "exit" ? v1::Command::Route::EXIT
                                                      : v1::Command::Route::BACKTRACK);
  const std::optional<v1::CommandReply> reply = Ask(device, route, std::chrono::seconds(5));
  if (!reply) return Refuse(res, 504, "no answer from the wearer's daemon");
  json path = json::array();
  for (const v1::PlanPoint& p : reply->route().path()) path.push_back({Mm(p.x()), Mm(p.y())});
  res.status = reply->ok() ? 200 : 409;
  res.set_content(json{{"device", device},
                       {"to", to},
                       {"ok", reply->ok()},
                       {"message", reply->message()},
                       {"length_m", Mm(reply->route().length_m())},
                       {"path", std::move(path)}}
                      .dump(-1, ' ', false, json::error_handler_t::replace),
                  "application/json");
}

void Dashboard::Impl::ServeLead(DashboardState& state) {
  http.Post("/api/markers", [this, &state](const httplib::Request& req, httplib::Response& res) {
    PostMarker(state, req, res);
  });
  // The lead acknowledges a wearer's alert: {"device"}; the wearer's daemon marks it
  // acknowledged (Command.acknowledge_alert) and every dashboard sees it so.
  http.Post("/api/alerts/ack", [this](const httplib::Request& req, httplib::Response& res) {
    const json body = json::parse(req.body, nullptr, false);
    const std::string device = body.is_object() ? body.value("device", "") : "";
    if (device.empty() || device.size() > 128) return Refuse(res, 400, "device is needed");
    v1::Command ack;
    ack.mutable_acknowledge_alert()->set_by(options.name);
    SendCommand(device, ack);
    res.status = 202;
    res.set_content(json{{"device", device}}.dump(), "application/json");
  });
  http.Post("/api/route",
            [this](const httplib::Request& req, httplib::Response& res) { PostRoute(req, res); });
}

int Dashboard::Impl::Bind() {
  http.set_logger([](const httplib::Request& req, const httplib::Response& res) {
    if (res.status >= 400) spdlog::info("{} {} -> {}", req.method, req.path, res.status);
  });
  // Address reuse only (a restart binds at once), never port sharing: a second dashboard
  // on a port in use is an error, not a silent half of the requests.
  http.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  if (options.port == 0) return http.bind_to_any_port(options.host);
  return http.bind_to_port(options.host, options.port) ? options.port : -1;
}

Dashboard::Dashboard(DashboardServerOptions options, std::vector<DashboardPlan> plans)
    : impl_(std::make_unique<Impl>()), state_(std::make_unique<DashboardState>(options.dashboard)) {
  Impl& m = *impl_;
  m.options = std::move(options);
  for (const DashboardPlan& p : plans) m.rooms[p.plan.id] = std::make_unique<RoomMap>(p.plan);
  m.plans_json = PlansJson(plans, m.rooms);
  if (m.options.cot) {
    const std::vector<CotPlan> placed = CotPlansOf(plans);
    if (placed.empty())
      spdlog::warn("CoT: no plan is georeferenced, so no wearer can be sent (docs/cot.md)");
    m.cot = std::make_unique<CotBridge>(placed, *m.options.cot);
    std::string error;
    if (!m.cot->Open(&error)) throw std::runtime_error(error);
    spdlog::info("CoT to {} for {} georeferenced plans", m.options.cot->to, placed.size());
  }
  m.JoinDds();
  m.LoadMarkers(*state_);
  // One thread per open event stream: a team's few dashboards, not the public.
  m.http.new_task_queue = [] { return new httplib::ThreadPool(64); };
  m.ServeReads(*state_);
  m.ServeEvents(*state_);
  m.ServeLead(*state_);
  port_ = m.Bind();
  if (port_ <= 0)
    throw std::runtime_error("cannot listen on " + m.options.host + ":" +
                             std::to_string(m.options.port));
  m.dds_thread = std::thread([this] { impl_->ReadDds(*state_); });
}

Dashboard::~Dashboard() {
  Stop();
  if (impl_->dds_thread.joinable()) impl_->dds_thread.join();
}

void Dashboard::Serve() { impl_->http.listen_after_bind(); }

void Dashboard::Stop() {
  impl_->stop = true;
  impl_->reply_cv.notify_all();
  state_->Stop();
  impl_->waiter->Wake();
  impl_->http.stop();
}

int DashboardPortFromLog(const std::string& log_path, std::chrono::milliseconds timeout) {
  const std::regex line(R"(dashboard on http://[^:/]+:(\d+)/)");
  const auto deadline = Clock::now() + timeout;
  while (true) {
    std::ifstream in(log_path);
    const std::string text{std::istreambuf_iterator<char>(in), {}};
    std::smatch m;
    if (std::regex_search(text, m, line)) return std::stoi(m[1]);
    if (Clock::now() > deadline) return 0;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

}  // namespace floorpose::tools
