#include "core/register/gicp.h"

#include <pcl/registration/gicp.h>

#include "core/search/flann_tree.h"

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
  FlannTree tree;
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
  q.fitness = source.empty() ? 0.0 : static_cast<double>(q.overlap_points) / static_cast<double>(source.size());
  return q;
}

Eigen::Vector3d centroid(const Cloud& cloud) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const pcl::PointXYZ& p : cloud) sum += p.getVector3fMap().cast<double>();
  return cloud.empty() ? sum : Eigen::Vector3d(sum / static_cast<double>(cloud.size()));
}

namespace {

Cloud::Ptr shifted(const Cloud& cloud, const Eigen::Vector3f& by) {
  auto out = std::make_shared<Cloud>(cloud);
  for (pcl::PointXYZ& p : *out) p.getVector3fMap() += by;
  return out;
}

struct GicpPass {
  Eigen::Matrix4f transform;
  bool converged = false;
};

GicpPass gicp_pass(const Cloud::ConstPtr& target, const Cloud::ConstPtr& source, const Eigen::Matrix4f& guess,
                   double max_correspondence_m, double convergence, const GicpConfig& config) {
  pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> gicp;
  // PCL's own trees, searched without FLANN's per-query parallel region (flann_tree.h).
  gicp.setSearchMethodTarget(std::make_shared<FlannTree>());
  gicp.setSearchMethodSource(std::make_shared<FlannTree>());
  gicp.setInputTarget(target);
  gicp.setInputSource(source);
  gicp.setMaxCorrespondenceDistance(max_correspondence_m);
  gicp.setMaximumIterations(config.max_iterations);
  gicp.setTransformationEpsilon(convergence);
  gicp.setCorrespondenceRandomness(config.neighbours);
  Cloud aligned;
  gicp.align(aligned, guess);
  return {gicp.getFinalTransformation(), gicp.hasConverged()};
}

}  // namespace

Registration register_gicp(const Cloud::ConstPtr& target, const Cloud::ConstPtr& source,
                           const Eigen::Isometry3d& guess, const GicpConfig& config) {
  // GICP's rotation is about the cloud frame's origin, which sits at the middle ping, tens of
  // metres from an adjacent line's overlap: yaw and translation are then nearly the same motion
  // and the solver stalls short of the minimum. Registering about the clouds' centroids
  // decouples them.
  const Eigen::Vector3f target_centre = config.about_centroid ? Eigen::Vector3f(centroid(*target).cast<float>()) : Eigen::Vector3f::Zero();
  const Eigen::Vector3f source_centre = config.about_centroid ? Eigen::Vector3f(centroid(*source).cast<float>()) : Eigen::Vector3f::Zero();
  const Eigen::Isometry3d to_target_centre(Eigen::Translation3d(-target_centre.cast<double>()));
  const Eigen::Isometry3d from_source_centre(Eigen::Translation3d(source_centre.cast<double>()));
  const Cloud::Ptr centred_target = shifted(*target, -target_centre);
  const Cloud::Ptr centred_source = shifted(*source, -source_centre);
  const Eigen::Isometry3d centred_guess = to_target_centre * guess * from_source_centre;

  GicpPass pass = gicp_pass(centred_target, centred_source, centred_guess.matrix().cast<float>(),
                            config.max_correspondence_m, config.convergence, config);
  if (config.refine_correspondence_m > 0) {
    const GicpPass refined = gicp_pass(centred_target, centred_source, pass.transform,
                                       config.refine_correspondence_m, config.refine_convergence, config);
    pass = {refined.transform, pass.converged && refined.converged};
  }
  Eigen::Isometry3d centred_result;
  centred_result.matrix() = pass.transform.cast<double>();
  const Eigen::Isometry3d result = to_target_centre.inverse() * centred_result * from_source_centre.inverse();
  Registration r;
  r.source_to_target = result;
  // Re-orthonormalise: the float transform drifts from a rotation by ~1e-7.
  r.source_to_target.linear() = Eigen::Quaterniond(r.source_to_target.rotation()).normalized().toRotationMatrix();
  r.quality = overlap_quality(*target, *source, r.source_to_target, config.max_correspondence_m);
  r.quality.converged = pass.converged;
  return r;
}

}  // namespace bathyslam
