#include "core/graph/relative_pose_cost.h"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "core/graph/dr_noise.h"  // skew
#include "core/graph/relative_pose_error.h"

namespace bathyslam {
namespace {

// The quaternion (v, 0).
Eigen::Quaterniond pure(const Eigen::Vector3d& v) { return Eigen::Quaterniond(0, v.x(), v.y(), v.z()); }

// PlusJacobian of EigenQuaternionManifold at q (coordinates x, y, z, w by rows): column i is
// (eᵢ, 0) ⊗ q.
Eigen::Matrix<double, 4, 3> plus_jacobian(const Eigen::Quaterniond& q) {
  Eigen::Matrix<double, 4, 3> p;
  for (int i = 0; i < 3; ++i) p.col(i) = (pure(Eigen::Vector3d::Unit(i)) * q).coeffs();
  return p;
}

}  // namespace

Information6 square_root(const Information6& information) {
  const Eigen::SelfAdjointEigenSolver<Information6> eigen(information);
  const Eigen::Matrix<double, 6, 1> roots = eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return roots.asDiagonal() * eigen.eigenvectors().transpose();
}

RelativePoseCost::RelativePoseCost(const PoseGraphEdge& edge)
    : anchor_(edge.anchor),
      anchor_measured_(edge.measured * edge.anchor),
      q_measured_(Eigen::Quaterniond(edge.measured.rotation()).normalized()),
      sqrt_information_(square_root(edge.information)) {}

// With Z = Rz(−ψ_a) (ψ_a the yaw of a), T = Z·R_a the level frame's rotation and A = q_m ⊗ q_b⁻¹:
//   translation  e_t = Z·(R_b·anchor + p_b − p_a) − T·anchor_measured
//   rotation     e_r = T·v,  v = 2·vec(A ⊗ q_a)
// A turn θ of a node (R ← exp(θ)·R) is δ = θ/2 of the manifold, and turns its yaw by g·θ,
// g = (−R₀₀R₂₀, −R₁₀R₂₀, R₀₀² + R₁₀²) / (R₀₀² + R₁₀²) (the first column's heading).
bool RelativePoseCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> p_a(parameters[0]), p_b(parameters[1]);
  const Eigen::Map<const Eigen::Quaterniond> q_a(parameters[0] + 3), q_b(parameters[1] + 3);
  Eigen::Map<Eigen::Matrix<double, 6, 1>> r(residuals);
  const Eigen::Matrix<double, 6, 1> error =
      relative_pose_error<double>(p_a, q_a, p_b, q_b, anchor_, anchor_measured_, q_measured_);
  r = sqrt_information_ * error;
  if (jacobians == nullptr || (jacobians[0] == nullptr && jacobians[1] == nullptr)) return true;

  const Eigen::Matrix3d r_a = q_a.toRotationMatrix();
  const double h2 = r_a(0, 0) * r_a(0, 0) + r_a(1, 0) * r_a(1, 0);
  const Eigen::RowVector3d g(-r_a(0, 0) * r_a(2, 0) / h2, -r_a(1, 0) * r_a(2, 0) / h2, 1.0);
  const double c = r_a(0, 0) / std::sqrt(h2), s = r_a(1, 0) / std::sqrt(h2);
  Eigen::Matrix3d z;  // Rz(−ψ_a)
  z << c, s, 0, -s, c, 0, 0, 0, 1;
  const Eigen::Matrix3d turn_z = skew(Eigen::Vector3d::UnitZ());
  const Eigen::Vector3d e_t = error.head<3>(), e_r = error.tail<3>();
  const Eigen::Quaterniond a = q_measured_ * q_b.conjugate();
  const Eigen::Vector3d v = 2.0 * (a * q_a).vec();
  Eigen::Matrix3d m;  // ∂ vec(A ⊗ q_a) / ∂δ_a; it is −∂/∂δ_b
  for (int i = 0; i < 3; ++i) m.col(i) = (a * pure(Eigen::Vector3d::Unit(i)) * q_a).vec();
  const Eigen::Matrix3d t = z * r_a;

  using Block = Eigen::Matrix<double, 6, 6>;  // ∂error / ∂(p, δ)
  using Jacobian = Eigen::Matrix<double, 6, 7, Eigen::RowMajor>;
  if (jacobians[0] != nullptr) {
    Block d = Block::Zero();
    d.block<3, 3>(0, 0) = -z;
    d.block<3, 3>(0, 3) = 2.0 * (-turn_z * e_t * g + z * skew(r_a * anchor_measured_));
    d.block<3, 3>(3, 3) = 2.0 * (-turn_z * e_r * g - z * skew(r_a * v)) + 2.0 * t * m;
    Eigen::Map<Jacobian> j(jacobians[0]);
    j.leftCols<3>() = sqrt_information_ * d.leftCols<3>();
    j.rightCols<4>() = sqrt_information_ * d.rightCols<3>() * plus_jacobian(q_a).transpose();
  }
  if (jacobians[1] != nullptr) {
    Block d = Block::Zero();
    d.block<3, 3>(0, 0) = z;
    d.block<3, 3>(0, 3) = -2.0 * z * skew(q_b * anchor_);
    d.block<3, 3>(3, 3) = -2.0 * t * m;
    Eigen::Map<Jacobian> j(jacobians[1]);
    j.leftCols<3>() = sqrt_information_ * d.leftCols<3>();
    j.rightCols<4>() = sqrt_information_ * d.rightCols<3>() * plus_jacobian(q_b).transpose();
  }
  return true;
}

}  // namespace bathyslam
