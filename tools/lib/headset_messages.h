// Simulated headset output as the wire messages a HoloLens app would publish.
#pragma once

#include <cstdint>

#include "core/frames.h"
#include "core/sim/demo_walk.h"
#include "floorpose/v1/floorpose.pb.h"

namespace floorpose::tools {

// The slam-frame mesh as a MeshDelta in the headset's own convention.
v1::MeshDelta ToMeshDelta(const sim::SimMesh& mesh, HeadsetFrame frame, int64_t stamp_ns);
// A horizontal slam pose (heading = viewing direction) as a HeadsetPose.
v1::HeadsetPose ToHeadsetPose(const Pose2& pose_slam, HeadsetFrame frame, int64_t stamp_ns);
// A wall pick (slam / plan frames) as a Command, in the headset's convention; the headset
// point at slam height height_m.
v1::Command ToWallPickCommand(const WallPick& pick, double height_m, HeadsetFrame frame,
                              uint64_t request_id);
// The walk's wall pick as a Command, in the headset's convention.
v1::Command ToWallPickCommand(const sim::DemoWalk& walk, HeadsetFrame frame, uint64_t request_id);

}  // namespace floorpose::tools
