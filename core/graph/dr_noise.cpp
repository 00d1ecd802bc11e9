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

void DrNoiseModel::StepSums::add(const Eigen::Matrix3d& step_qt, const Eigen::Matrix3d& step_qr, const Eigen::Matrix3d& s) {
  qt += step_qt;
  qr += step_qr;
  s_qr += s * step_qr;
  s_qr_s += s * step_qr * s.transpose();
}

DrNoiseModel::StepSums& DrNoiseModel::StepSums::operator+=(const StepSums& other) {
  qt += other.qt;
  qr += other.qr;
  s_qr += other.s_qr;
  s_qr_s += other.s_qr_s;
  return *this;
}

DrNoiseModel::StepSums DrNoiseModel::StepSums::operator-(const StepSums& other) const {
  StepSums d = *this;
  d.qt -= other.qt;
  d.qr -= other.qr;
  d.s_qr -= other.s_qr;
  d.s_qr_s -= other.s_qr_s;
  return d;
}

DrNoiseModel::DrNoiseModel(const std::vector<Eigen::Isometry3d>& dead_reckoning, const GraphConfig& config) {
  const int n = static_cast<int>(dead_reckoning.size());
  for (const Eigen::Isometry3d& pose : dead_reckoning) level_.push_back(level_frame(pose));
  origin_ = n > 0 ? Eigen::Vector3d(level_[0].translation()) : Eigen::Vector3d::Zero();
  const auto in_map_axes = [&](const Eigen::Vector3d& sigma, int node) {
    const Eigen::Matrix3d& heading = level_[node].linear();
    return Eigen::Matrix3d(heading * Eigen::Matrix3d(sigma.cwiseAbs2().asDiagonal()) * heading.transpose());
  };
  prefix_.assign(std::max(n, 1), StepSums{});
  start_of_.assign(std::max(n, 1), 0);
  for (int m = 0; m + 1 < n; ++m) {
    prefix_[m + 1] = prefix_[m];
    start_of_[m + 1] = config.has_step(m) ? start_of_[m] : m + 1;
    if (!config.has_step(m)) continue;  // node m + 1 starts another survey
    prefix_[m + 1].add(in_map_axes(config.dr_sigma_translation_m, m), in_map_axes(config.rotation_sigma_of_step(m), m),
                       skew(level_[m + 1].translation() - origin_));
  }
  // A datum edge's noise is both start fixes' (datum_information), in node 0's frame as the edge's.
  for (int start : config.survey_starts) {
    if (start <= 0 || start >= n) continue;
    StepSums& datum = datum_[start];
    datum.add(2 * in_map_axes(config.start_sigma_translation_m, 0), 2 * in_map_axes(config.start_sigma_rotation_rad, 0),
              skew(level_[start].translation() - origin_));
  }
}

Eigen::Isometry3d DrNoiseModel::relative_pose(int from, int to) const {
  return level_.at(from).inverse() * level_.at(to);
}

DrNoiseModel::StepSums DrNoiseModel::path_from_datum(int node) const {
  const int start = start_of_[node];
  StepSums path = prefix_[node] - prefix_[start];
  if (const auto datum = datum_.find(start); datum != datum_.end()) path += datum->second;
  return path;
}

// In map axes, holding `from` fixed, step m's noise (translation w_t, rotation w_r) moves `to`
// by w_t + w_r × d_m and turns it by w_r, d_m = p_to − s_m, whichever side of the step `from`
// lies on. With D = [p_to]ₓ and S_m = [s_m]ₓ, [d_m]ₓ = D − S_m, and summed over the steps between
// them (along one survey's chain, or from each through its survey's start to the datum)
//   translation:  Σ Qt + Σ (D − S)Qr(D − S)ᵀ = Σ Qt + D ΣQr Dᵀ − D (ΣSQr)ᵀ − ΣSQr Dᵀ + ΣSQrSᵀ
//   cross:        −Σ (D − S)Qr = ΣSQr − D ΣQr
//   rotation:     Σ Qr
// which prefix sums give in O(1).
Covariance6 DrNoiseModel::covariance(int from, int to) const {
  const int lo = std::min(from, to), hi = std::max(from, to);
  if (lo < 0 || hi >= size()) throw std::out_of_range("DrNoiseModel: node out of range");
  StepSums steps;
  if (start_of_[lo] == start_of_[hi]) {
    steps = prefix_[hi] - prefix_[lo];
  } else {
    steps = path_from_datum(lo);
    steps += path_from_datum(hi);
  }
  const Eigen::Matrix3d d = skew(level_[to].translation() - origin_);

  Covariance6 map_axes;
  map_axes.topLeftCorner<3, 3>() =
      steps.qt + d * steps.qr * d.transpose() - d * steps.s_qr.transpose() - steps.s_qr * d.transpose() + steps.s_qr_s;
  map_axes.topRightCorner<3, 3>() = steps.s_qr - d * steps.qr;
  map_axes.bottomLeftCorner<3, 3>() = map_axes.topRightCorner<3, 3>().transpose();
  map_axes.bottomRightCorner<3, 3>() = steps.qr;

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
