#include "core/register/gicp.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/registration/gicp.h>

namespace bathyslam {

Cloud::Ptr crop_to_overlap(const Cloud& cloud, const Cloud& other, const Eigen::Isometry3d& cloud_to_other,
                           double margin_m) {
  Eigen::Vector2f lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  for (const pcl::PointXYZ& p : other) {
    lo = lo.cwiseMin(p.getVector3fMap().head<2>());
    hi = hi.cwiseMax(p.getVector3fMap().head<2>());
  }
  lo.array() -= static_cast<float>(margin_m);
  hi.array() += static_cast<float>(margin_m);
  const Eigen::Isometry3f t = cloud_to_other.cast<float>();
  auto cropped = std::make_shared<Cloud>();
  for (const pcl::PointXYZ& p : cloud) {
    const Eigen::Vector2f q = (t * p.getVector3fMap()).head<2>();
    if ((q.array() >= lo.array()).all() && (q.array() <= hi.array()).all()) cropped->push_back(p);
  }
  return cropped;
}

Eigen::Isometry3d keep_dr_roll_pitch(const Eigen::Isometry3d& registered, const Eigen::Isometry3d& guess,
                                     const Eigen::Vector3d& anchor) {
  // The change GICP made to the guess's rotation, reduced to its turn about the target's
  // vertical axis (z, down in a vehicle frame).
  const Eigen::Matrix3d delta = registered.rotation() * guess.rotation().transpose();
  const double yaw = std::atan2(delta(1, 0), delta(0, 0));
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * guess.rotation();
  out.translation() = registered * anchor - out.linear() * anchor;
  return out;
}

RegistrationQuality overlap_quality(const Cloud& target, const Cloud& source,
                                    const Eigen::Isometry3d& source_to_target, double max_distance_m) {
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(target.makeShared());
  const Eigen::Isometry3f t = source_to_target.cast<float>();
  RegistrationQuality q;
  std::vector<int> index(1);
  std::vector<float> sq_distance(1);
  double sum = 0;
  const double max_sq = max_distance_m * max_distance_m;
  for (const pcl::PointXYZ& p : source) {
    const Eigen::Vector3f moved = t * p.getVector3fMap();
    if (tree.nearestKSearch(pcl::PointXYZ(moved.x(), moved.y(), moved.z()), 1, index, sq_distance) == 1 &&
        sq_distance[0] <= max_sq) {
      ++q.overlap_points;
      sum += sq_distance[0];
    }
  }
  q.overlap_mse_m2 = q.overlap_points > 0 ? sum / q.overlap_points : 0.0;
  return q;
}

Registration register_gicp(const Cloud::ConstPtr& target, const Cloud::ConstPtr& source,
                           const Eigen::Isometry3d& guess, const GicpConfig& config) {
  pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> gicp;
  gicp.setInputTarget(target);
  gicp.setInputSource(source);
  gicp.setMaxCorrespondenceDistance(config.max_correspondence_m);
  gicp.setMaximumIterations(config.max_iterations);
  gicp.setTransformationEpsilon(config.convergence);
  gicp.setCorrespondenceRandomness(config.neighbours);
  Cloud aligned;
  gicp.align(aligned, guess.matrix().cast<float>());

  Registration r;
  r.source_to_target.matrix() = gicp.getFinalTransformation().cast<double>();
  // Re-orthonormalise: the float transform drifts from a rotation by ~1e-7.
  r.source_to_target.linear() = Eigen::Quaterniond(r.source_to_target.rotation()).normalized().toRotationMatrix();
  r.quality = overlap_quality(*target, *source, r.source_to_target, config.max_correspondence_m);
  r.quality.converged = gicp.hasConverged();
  r.quality.fitness = gicp.getFitnessScore(config.max_correspondence_m);
  return r;
}

}  // namespace bathyslam
