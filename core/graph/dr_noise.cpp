#include "core/graph/dr_noise.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace bathyslam {
namespace {

Eigen::Matrix3d heading_rotation(const Eigen::Matrix3d& rotation) {
  const double yaw = std::atan2(rotation(1, 0), rotation(0, 0));
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

// (Σ over m in [lo, hi)) of a prefix-summed quantity.
Eigen::Matrix3d range_sum(const std::vector<Eigen::Matrix3d>& prefix, int lo, int hi) {
  return prefix[hi] - prefix[lo];
}

}  // namespace

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Isometry3d level_frame(const Eigen::Isometry3d& pose) {
  Eigen::Isometry3d level = Eigen::Isometry3d::Identity();
  level.linear() = heading_rotation(pose.linear());
  level.translation() = pose.translation();
  return level;
}

Eigen::Isometry3d between_level_frames(const Eigen::Isometry3d& relative, const Eigen::Isometry3d& from_pose,
                                       const Eigen::Isometry3d& to_pose) {
  return level_frame(from_pose).inverse() * from_pose * relative * to_pose.inverse() * level_frame(to_pose);
}

DrNoiseModel::DrNoiseModel(const std::vector<Eigen::Isometry3d>& dead_reckoning, const GraphConfig& config) {
  const int n = static_cast<int>(dead_reckoning.size());
  for (const Eigen::Isometry3d& pose : dead_reckoning) level_.push_back(level_frame(pose));
  origin_ = n > 0 ? Eigen::Vector3d(level_[0].translation()) : Eigen::Vector3d::Zero();
  const Eigen::Matrix3d sigma_t = config.dr_sigma_translation_m.cwiseAbs2().asDiagonal();
  const Eigen::Matrix3d zero = Eigen::Matrix3d::Zero();
  sum_qt_.assign(std::max(n, 1), zero);
  sum_qr_.assign(std::max(n, 1), zero);
  sum_s_qr_.assign(std::max(n, 1), zero);
  sum_s_qr_s_.assign(std::max(n, 1), zero);
  for (int m = 0; m + 1 < n; ++m) {
    const Eigen::Matrix3d& heading = level_[m].linear();
    const Eigen::Matrix3d qt = heading * sigma_t * heading.transpose();
    const Eigen::Matrix3d sigma_r = config.rotation_sigma_of_step(m).cwiseAbs2().asDiagonal();
    const Eigen::Matrix3d qr = heading * sigma_r * heading.transpose();
    const Eigen::Matrix3d s = skew(level_[m + 1].translation() - origin_);
    sum_qt_[m + 1] = sum_qt_[m] + qt;
    sum_qr_[m + 1] = sum_qr_[m] + qr;
    sum_s_qr_[m + 1] = sum_s_qr_[m] + s * qr;
    sum_s_qr_s_[m + 1] = sum_s_qr_s_[m] + s * qr * s.transpose();
  }
}

Eigen::Isometry3d DrNoiseModel::relative_pose(int from, int to) const {
  return level_.at(from).inverse() * level_.at(to);
}

// In map axes, holding `from` fixed, step m's noise (translation w_t, rotation w_r) moves `to`
// by w_t + w_r × d_m and turns it by w_r, d_m = p_to − s_m, whichever side of the step `from`
// lies on. With D = [p_to]ₓ and S_m = [s_m]ₓ, [d_m]ₓ = D − S_m, and summed over the steps
//   translation:  Σ Qt + Σ (D − S)Qr(D − S)ᵀ = Σ Qt + D ΣQr Dᵀ − D (ΣSQr)ᵀ − ΣSQr Dᵀ + ΣSQrSᵀ
//   cross:        −Σ (D − S)Qr = ΣSQr − D ΣQr
//   rotation:     Σ Qr
// which prefix sums give in O(1).
Covariance6 DrNoiseModel::covariance(int from, int to) const {
  const int lo = std::min(from, to), hi = std::max(from, to);
  if (lo < 0 || hi >= size()) throw std::out_of_range("DrNoiseModel: node out of range");
  const Eigen::Matrix3d qt = range_sum(sum_qt_, lo, hi);
  const Eigen::Matrix3d qr = range_sum(sum_qr_, lo, hi);
  const Eigen::Matrix3d s_qr = range_sum(sum_s_qr_, lo, hi);
  const Eigen::Matrix3d s_qr_s = range_sum(sum_s_qr_s_, lo, hi);
  const Eigen::Matrix3d d = skew(level_[to].translation() - origin_);

  Covariance6 map_axes;
  map_axes.topLeftCorner<3, 3>() = qt + d * qr * d.transpose() - d * s_qr.transpose() - s_qr * d.transpose() + s_qr_s;
  map_axes.topRightCorner<3, 3>() = s_qr - d * qr;
  map_axes.bottomLeftCorner<3, 3>() = map_axes.topRightCorner<3, 3>().transpose();
  map_axes.bottomRightCorner<3, 3>() = qr;

  Covariance6 to_level = Covariance6::Zero();
  to_level.topLeftCorner<3, 3>() = level_[from].linear().transpose();
  to_level.bottomRightCorner<3, 3>() = level_[from].linear().transpose();
  return to_level * map_axes * to_level.transpose();
}

Covariance6 dr_relative_covariance(const std::vector<Eigen::Isometry3d>& dead_reckoning, int from, int to,
                                   const GraphConfig& config) {
  return DrNoiseModel(dead_reckoning, config).covariance(from, to);
}

Covariance6 covariance_from_information(const Information6& information, double unobserved_variance) {
  const Eigen::SelfAdjointEigenSolver<Information6> eigen(information);
  Vector6 variances;
  for (int i = 0; i < 6; ++i) {
    const double lambda = eigen.eigenvalues()(i);
    variances(i) = lambda * unobserved_variance > 1.0 ? 1.0 / lambda : unobserved_variance;
  }
  return eigen.eigenvectors() * variances.asDiagonal() * eigen.eigenvectors().transpose();
}

Covariance6 measurement_covariance(const PoseGraphEdge& edge, const Eigen::Isometry3d& from_pose,
                                   double unobserved_variance) {
  Covariance6 covariance = covariance_from_information(edge.information, unobserved_variance);

  // The cost's error and this parametrisation's noise differ in the sign of the rotation part.
  const Vector6 signs = (Vector6() << 1, 1, 1, -1, -1, -1).finished();
  covariance = signs.asDiagonal() * covariance * signs.asDiagonal();

  // Origin t = anchor point p − R·c: turning by δθ moves the origin by δθ × (−R·c) = [R·c]ₓ δθ.
  const Eigen::Matrix3d tilt = level_frame(from_pose).linear().transpose() * from_pose.linear();
  Covariance6 anchor_to_origin = Covariance6::Identity();
  anchor_to_origin.topRightCorner<3, 3>() = skew(tilt * (edge.measured.linear() * edge.anchor));
  return anchor_to_origin * covariance * anchor_to_origin.transpose();
}

Vector6 pose_difference(const Eigen::Isometry3d& measured, const Eigen::Isometry3d& predicted) {
  const Eigen::AngleAxisd turn(measured.linear() * predicted.linear().transpose());
  Vector6 difference;
  difference << measured.translation() - predicted.translation(), turn.angle() * turn.axis();
  return difference;
}

double mahalanobis2_xy_yaw(const Vector6& difference, const Covariance6& covariance) {
  const Eigen::Vector3d d(difference(0), difference(1), difference(5));
  return d.dot(xy_yaw_block(covariance).ldlt().solve(d));
}

PlausibilityTest plausibility(const Eigen::Isometry3d& measured, const Eigen::Isometry3d& dr_predicted,
                              const Covariance6& covariance, double chi2_threshold) {
  PlausibilityTest test;
  test.mahalanobis2 = mahalanobis2_xy_yaw(pose_difference(measured, dr_predicted), covariance);
  test.dof = 3;
  test.plausible = test.mahalanobis2 <= chi2_threshold;
  return test;
}

}  // namespace bathyslam
