// A peer's ICP beside ours in `floorpose bench registration`, in the same process: PCL's
// point-to-plane ICP, built only with -DFLOORPOSE_BENCH_PEERS=ON (Debian's libpcl-dev), so
// that the tool and its package never need PCL.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/floor_plan.h"
#include "core/se2.h"

namespace floorpose {

struct PeerFit {
  Se2 T_plan_slam;
  int iterations = 0;
  bool converged = false;
};

// pcl::IterativeClosestPointWithNormals with Levenberg-Marquardt point-to-plane steps on x,
// y and heading only (WarpPointRigid3D; the 6-DOF linear solve is singular on points of
// one height), against the plan's walls sampled every sample_m with their normals. The
// target's k-d tree is built once here, as our index is, and not timed.
class PclPointToPlaneIcp {
 public:
  PclPointToPlaneIcp(const FloorPlan& plan, double sample_m, double max_correspondence_m,
                     int max_iterations, double converge_translation_m);
  ~PclPointToPlaneIcp();
  PeerFit Align(const std::vector<Eigen::Vector2d>& points_slam, const Se2& initial) const;
  size_t target_points() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace floorpose
