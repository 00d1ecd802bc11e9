#pragma once
// The error of a relative-pose measurement between two poses, shared by the Ceres cost (with
// jets) and by the checks that read residuals after a solve (with doubles), so both see the same
// numbers.
#include <cmath>

#include <Eigen/Geometry>

#include "core/graph/pose_graph.h"

namespace bathyslam {

// Translation x, y, z then rotation about x, y, z, in `a`'s level frame (its heading only, z the
// true vertical), not its body frame: on flat ground a registration observes depth but not where
// along the bottom it lies, and in a body frame tilted half a degree a 20 m error along the bottom
// would show 0.17 m of it as "depth". The translation compares where `b`'s point `anchor` lands
// (estimate minus measurement); the rotation is the small-angle vector of measured * estimated⁻¹.
// Unwhitened.
template <typename T>
Eigen::Matrix<T, 6, 1> relative_pose_error(const Eigen::Matrix<T, 3, 1>& p_a, const Eigen::Quaternion<T>& q_a,
                                           const Eigen::Matrix<T, 3, 1>& p_b, const Eigen::Quaternion<T>& q_b,
                                           const Eigen::Vector3d& anchor, const Eigen::Vector3d& anchor_measured,
                                           const Eigen::Quaterniond& q_measured) {
  const Eigen::Quaternion<T> q_a_inverse = q_a.conjugate();
  const Eigen::Quaternion<T> q_ab = q_a_inverse * q_b;
  const Eigen::Matrix<T, 3, 1> p_ab = q_a_inverse * (p_b - p_a);
  const Eigen::Quaternion<T> delta_q = q_measured.template cast<T>() * q_ab.conjugate();

  const Eigen::Quaternion<T> tilt = level_from_body(q_a);

  Eigen::Matrix<T, 6, 1> error;
  error.template head<3>() =
      tilt * (q_ab * anchor.template cast<T>() + p_ab - anchor_measured.template cast<T>());
  error.template tail<3>() = tilt * (T(2.0) * delta_q.vec());
  return error;
}

}  // namespace bathyslam
