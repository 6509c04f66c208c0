#include "platform/team.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "platform/state_file.h"

namespace floorpose::platform {

bool ValidMarkerId(const std::string& id) {
  if (id.empty() || id.size() > 128) return false;
  return std::all_of(id.begin(), id.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.' ||
           c == ':' || c == '/';
  });
}

std::string MarkerKindName(v1::Marker::Kind kind) {
  std::string name = v1::Marker::Kind_Name(kind);
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name;
}

bool ParseMarkerKind(const std::string& name, v1::Marker::Kind* kind) {
  std::string upper = name;
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return v1::Marker::Kind_Parse(upper, kind) && *kind != v1::Marker::KIND_UNSPECIFIED;
}

MarkerBoard::Take MarkerBoard::Merge(const v1::Marker& m, std::string* why) {
  if (!ValidMarkerId(m.id())) {
    *why = "marker id '" + m.id().substr(0, 64) + "' is not one (letters, digits, - _ . : /)";
    return Take::kRefused;
  }
  if (!std::isfinite(m.x()) || !std::isfinite(m.y()) || !std::isfinite(m.radius_m()) ||
      m.radius_m() < 0 || std::abs(m.x()) > 1e6 || std::abs(m.y()) > 1e6 || m.radius_m() > 100) {
    *why = "marker " + m.id() + ": position or radius not finite or out of range";
    return Take::kRefused;
  }
  if (m.text().size() > 1024 || m.author().size() > 256 || m.plan_id().size() > 256) {
    *why = "marker " + m.id() + ": text, author or plan id too long";
    return Take::kRefused;
  }
  auto it = markers_.find(m.id());
  if (it != markers_.end()) {
    const v1::Marker& held = it->second;
    const bool newer = m.revision() != held.revision()
                           ? m.revision() > held.revision()
                           : m.created_unix_ns() > held.created_unix_ns();
    if (!newer) return Take::kKnown;
    it->second = m;
    ++revision_;
    return Take::kReplaced;
  }
  if (markers_.size() >= kCapacity) {
    // Room is made from the removed ones, oldest first; live markers are never dropped.
    auto oldest = markers_.end();
    for (auto i = markers_.begin(); i != markers_.end(); ++i)
      if (i->second.removed() && (oldest == markers_.end() ||
                                  i->second.created_unix_ns() < oldest->second.created_unix_ns()))
        oldest = i;
    if (oldest == markers_.end()) {
      *why = "marker " + m.id() + ": the board is full (" + std::to_string(kCapacity) + ")";
      return Take::kRefused;
    }
    markers_.erase(oldest);
  }
  markers_.emplace(m.id(), m);
  ++revision_;
  return Take::kNew;
}

std::vector<KeepOut> MarkerBoard::KeepOuts(const std::string& plan_id,
                                           const std::string& floor) const {
  std::vector<KeepOut> out;
  for (const auto& [id, m] : markers_) {
    if (m.removed() || m.plan_id() != plan_id || m.floor() != floor) continue;
    if (m.kind() != v1::Marker::HAZARD && m.kind() != v1::Marker::BLOCKED) continue;
    out.push_back({{m.x(), m.y()}, m.radius_m() > 0 ? m.radius_m() : kDefaultRadiusM});
  }
  return out;
}

bool MarkerBoard::Load(const std::string& path, std::string* error) {
  v1::MarkerSet set;
  switch (ReadStateFile(path, &set, error, uint64_t{64} << 20)) {
    case StateRead::kMissing: return true;
    case StateRead::kBad: return false;
    case StateRead::kOk: break;
  }
  std::string why;
  for (const v1::Marker& m : set.markers()) Merge(m, &why);
  return true;
}

bool MarkerBoard::Save(const std::string& path, std::string* error) const {
  v1::MarkerSet set;
  for (const auto& [id, m] : markers_) *set.add_markers() = m;
  return WriteStateFile(path, set, error);
}

bool Roster::Take(Topic topic, const Envelope& e, int64_t now_ns) {
  v1::PlanPose pose;
  v1::DaemonStatus status;
  if (topic == Topic::kPlanPose) {
    if (!pose.ParseFromString(e.payload) || !std::isfinite(pose.x()) || !std::isfinite(pose.y()))
      return false;
  } else if (topic != Topic::kStatus || !status.ParseFromString(e.payload)) {
    return false;
  }
  auto it = entries_.find(e.device_id);
  if (it == entries_.end()) {
    if (entries_.size() >= kCapacity || e.device_id.empty() || e.device_id.size() > 128)
      return false;
    it = entries_.emplace(e.device_id, Entry{}).first;
    it->second.teammate.set_device_id(e.device_id);
  }
  Entry& entry = it->second;
  if (topic == Topic::kPlanPose) {
    // A late pose (older than the one held) moves no one.
    if (entry.pose_received_ns != 0 &&
        pose.source_stamp_ns() < entry.teammate.pose().source_stamp_ns())
      return false;
    *entry.teammate.mutable_pose() = std::move(pose);
    entry.pose_received_ns = now_ns;
    return true;
  }
  entry.teammate.set_state(status.state());
  entry.teammate.set_plan_id(status.plan_id());
  *entry.teammate.mutable_alert() = std::move(*status.mutable_alert());
  return true;
}

std::vector<v1::Teammate> Roster::Teammates(int64_t now_ns) const {
  std::vector<v1::Teammate> out;
  out.reserve(entries_.size());
  for (const auto& [id, entry] : entries_) {
    out.push_back(entry.teammate);
    if (entry.pose_received_ns != 0)
      out.back().set_pose_age_s(static_cast<double>(now_ns - entry.pose_received_ns) * 1e-9);
  }
  return out;
}

}  // namespace floorpose::platform
