// What a daemon or a dashboard knows of the team beyond one wearer: the markers placed on
// the plans (floorpose/v1/marker) and every wearer's latest plan pose and state
// (floorpose/v1/plan_pose, floorpose/v1/status). Both are bounded, so a flood of ids
// cannot grow them without limit.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/route_planner.h"
#include "floorpose/v1/floorpose.pb.h"
#include "platform/dds.h"

namespace floorpose::platform {

// Markers by id, the highest revision of each (at equal revisions the later created).
class MarkerBoard {
 public:
  static constexpr size_t kCapacity = 4096;
  static constexpr double kDefaultRadiusM = 1.0;

  enum class Take { kNew, kReplaced, kKnown, kRefused };
  // A marker heard or placed: kept when it is new or newer than the one held. kRefused:
  // *why says what is wrong with it (an id that is not one, a non-finite position, full).
  Take Merge(const v1::Marker& marker, std::string* why);
  const std::map<std::string, v1::Marker>& markers() const { return markers_; }
  // Counts every change; a holder saves when it moved.
  uint64_t revision() const { return revision_; }

  // The areas routes keep out of on a plan's floor: HAZARD and BLOCKED markers not removed.
  std::vector<KeepOut> KeepOuts(const std::string& plan_id, const std::string& floor) const;

  // markers.pb (a MarkerSet in a state file, platform/state_file.h). Load merges what the
  // file holds; a missing file is no error.
  bool Load(const std::string& path, std::string* error);
  bool Save(const std::string& path, std::string* error) const;

 private:
  std::map<std::string, v1::Marker> markers_;
  uint64_t revision_ = 0;
};

// Letters, digits and - _ . : /, 1 to 128 of them.
bool ValidMarkerId(const std::string& id);

// A marker's kind as apps and people write it: "hazard", "victim", "searched", "blocked",
// "note". Parse refuses anything else, KIND_UNSPECIFIED's name included.
std::string MarkerKindName(v1::Marker::Kind kind);
bool ParseMarkerKind(const std::string& name, v1::Marker::Kind* kind);

// Every wearer's latest plan pose and daemon status, by device id.
class Roster {
 public:
  static constexpr size_t kCapacity = 256;
  // A plan pose or a status envelope; others, and payloads that do not parse, are ignored
  // (false). now_ns: the holder's clock, for the ages.
  bool Take(Topic topic, const Envelope& e, int64_t now_ns);
  std::vector<v1::Teammate> Teammates(int64_t now_ns) const;

 private:
  struct Entry {
    v1::Teammate teammate;
    int64_t pose_received_ns = 0;  // 0: no pose yet
  };
  std::map<std::string, Entry> entries_;
};

}  // namespace floorpose::platform
