#include "tools/floorpose/bench_peers.h"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>
#include <pcl/registration/transformation_estimation_point_to_plane.h>
#include <pcl/registration/warp_point_rigid_3d.h>
#include <pcl/search/kdtree.h>

#include <cmath>

namespace floorpose {

using Point = pcl::PointNormal;
using Cloud = pcl::PointCloud<Point>;

namespace {

// A plan point with its normal (zero for none), at height 0.
Point ToPoint(const Eigen::Vector2d& p, const Eigen::Vector2d& n) {
  Point q;
  q.x = static_cast<float>(p.x());
  q.y = static_cast<float>(p.y());
  q.z = 0;
  q.normal_x = static_cast<float>(n.x());
  q.normal_y = static_cast<float>(n.y());
  q.normal_z = 0;
  return q;
}

}  // namespace

struct PclPointToPlaneIcp::Impl {
  Cloud::Ptr target{new Cloud};
  pcl::search::KdTree<Point>::Ptr tree{new pcl::search::KdTree<Point>};
  double max_correspondence_m = 0;
  int max_iterations = 0;
  double converge_translation_m = 0;
};

PclPointToPlaneIcp::PclPointToPlaneIcp(const FloorPlan& plan, double sample_m,
                                       double max_correspondence_m, int max_iterations,
                                       double converge_translation_m)
    : impl_(std::make_unique<Impl>()) {
  impl_->max_correspondence_m = max_correspondence_m;
  impl_->max_iterations = max_iterations;
  impl_->converge_translation_m = converge_translation_m;
  for (const Segment& s : plan.segments) {
    const Eigen::Vector2d n = s.Normal();
    const int steps = std::max(1, static_cast<int>(std::ceil(s.Length() / sample_m)));
    for (int k = 0; k <= steps; ++k)
      impl_->target->push_back(ToPoint(s.a + (s.b - s.a) * (static_cast<double>(k) / steps), n));
  }
  impl_->tree->setInputCloud(impl_->target);
}

PclPointToPlaneIcp::~PclPointToPlaneIcp() = default;

size_t PclPointToPlaneIcp::target_points() const { return impl_->target->size(); }

PeerFit PclPointToPlaneIcp::Align(const std::vector<Eigen::Vector2d>& points_slam,
                                  const Se2& initial) const {
  Cloud::Ptr source(new Cloud);
  source->reserve(points_slam.size());
  for (const Eigen::Vector2d& p : points_slam)
    source->push_back(ToPoint(p, Eigen::Vector2d::Zero()));
  // PCL's iteration count is protected.
  struct Icp : pcl::IterativeClosestPointWithNormals<Point, Point, float> {
    int iterations() const { return nr_iterations_; }
  };
  using Estimation = pcl::registration::TransformationEstimationPointToPlane<Point, Point, float>;
  auto estimation = std::make_shared<Estimation>();
  estimation->setWarpFunction(
      std::make_shared<pcl::registration::WarpPointRigid3D<Point, Point, float>>());
  Icp icp;
  icp.setTransformationEstimation(estimation);
  icp.setInputSource(source);
  icp.setInputTarget(impl_->target);
  icp.setSearchMethodTarget(impl_->tree, true);  // built once, in the constructor
  icp.setMaxCorrespondenceDistance(static_cast<float>(impl_->max_correspondence_m));
  icp.setMaximumIterations(impl_->max_iterations);
  // PCL stops on the squared translation of a step.
  icp.setTransformationEpsilon(impl_->converge_translation_m * impl_->converge_translation_m);
  Eigen::Matrix4f guess = Eigen::Matrix4f::Identity();
  guess.topLeftCorner<2, 2>() = initial.R().cast<float>();
  guess.block<2, 1>(0, 3) = initial.t.cast<float>();
  Cloud aligned;
  icp.align(aligned, guess);
  const Eigen::Matrix4f T = icp.getFinalTransformation();
  PeerFit fit;
  fit.T_plan_slam = Se2{std::atan2(static_cast<double>(T(1, 0)), static_cast<double>(T(0, 0))),
                        {T(0, 3), T(1, 3)}};
  fit.iterations = icp.iterations();
  fit.converged = icp.hasConverged();
  return fit;
}

}  // namespace floorpose
