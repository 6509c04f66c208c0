// Which floor of a .floors set the headset is on, from its SLAM height: heights are taken
// relative to the floor in use when it was taken (the SLAM's z has its own zero), and
// another floor is taken once the height has stayed within floors.change_margin_m of it
// for floors.change_hold_s (a wearer on the stairs does not flicker between floors).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "platform/floor_plan_io.h"

namespace floorpose::platform {

class FloorFollower {
 public:
  // A new set (empty for a single plan): nothing observed yet.
  void Reset(FloorSet set);

  struct Change {
    const FloorEntry* to = nullptr;
    double height_m = 0;  // the headset's height on the set, as the SLAM says
  };
  // A pose's SLAM z at stamp_ns while floor `current` is in use: the floor to change to
  // now, if the height has said so long enough.
  std::optional<Change> Observe(const std::string& current, double slam_z, int64_t stamp_ns,
                                double margin_m, double hold_s);
  // The change was made: heights from here on are relative to `to` at slam_z.
  void Changed(const FloorEntry& to, double slam_z);

 private:
  FloorSet set_;
  struct Reference {  // the headset's slam z when the floor in use was taken
    double slam_z = 0, height_m = 0;
  };
  std::optional<Reference> reference_;
  struct Candidate {  // another floor the height has said since
    std::string id;
    int64_t since_ns = 0;
  };
  std::optional<Candidate> candidate_;
};

}  // namespace floorpose::platform
