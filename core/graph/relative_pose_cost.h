#pragma once
// A relative-pose edge as a Ceres cost on two nodes (position, then the unit quaternion as Eigen
// stores it: x, y, z, w), with its Jacobian written out: the graph solves during registration
// re-solve up to the whole survey after each batch, and automatic differentiation of the level
// frame (a yaw taken out of the quaternion) was a third of their time.
#include <ceres/sized_cost_function.h>

#include "core/graph/pose_graph.h"

namespace bathyslam {

// relative_pose_error whitened by the square root of the edge's information. The Jacobian is
// taken along ceres::EigenQuaternionManifold's tangent (q ← exp(δ) ⊗ q) and returned in the
// quaternion's four coordinates as J_tangent · Pᵀ, P being the manifold's PlusJacobian: P has
// orthonormal columns, so the solver's J · P is J_tangent exactly.
class RelativePoseCost final : public ceres::SizedCostFunction<6, 7, 7> {
 public:
  explicit RelativePoseCost(const PoseGraphEdge& edge);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Eigen::Vector3d anchor_;           // in `to`'s frame
  Eigen::Vector3d anchor_measured_;  // where the measurement puts it in `from`'s frame
  Eigen::Quaterniond q_measured_;
  Information6 sqrt_information_;
};

// S with SᵀS = information. Not Cholesky: an edge may leave directions it does not observe at
// zero information, and Cholesky of a singular matrix divides by zero.
Information6 square_root(const Information6& information);

}  // namespace bathyslam
