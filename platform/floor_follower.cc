#include "platform/floor_follower.h"

#include <cmath>

namespace floorpose::platform {

void FloorFollower::Reset(FloorSet set) {
  set_ = std::move(set);
  reference_.reset();
  candidate_.reset();
}

std::optional<FloorFollower::Change> FloorFollower::Observe(const std::string& current,
                                                            double slam_z, int64_t stamp_ns,
                                                            double margin_m, double hold_s) {
  const FloorEntry* in_use = set_.Find(current);
  if (set_.floors.size() < 2 || !in_use) return std::nullopt;
  if (!reference_) {
    reference_ = Reference{slam_z, in_use->height_m};
    return std::nullopt;
  }
  const double height = reference_->height_m + (slam_z - reference_->slam_z);
  const FloorEntry& nearest = set_.Nearest(height);
  if (nearest.id == current || std::abs(height - nearest.height_m) > margin_m) {
    candidate_.reset();
    return std::nullopt;
  }
  if (!candidate_ || candidate_->id != nearest.id) {
    candidate_ = Candidate{nearest.id, stamp_ns};
    return std::nullopt;
  }
  if (static_cast<double>(stamp_ns - candidate_->since_ns) * 1e-9 < hold_s) return std::nullopt;
  candidate_.reset();
  return Change{&nearest, height};
}

void FloorFollower::Changed(const FloorEntry& to, double slam_z) {
  reference_ = Reference{slam_z, to.height_m};
}

}  // namespace floorpose::platform
