#include "core/graph/pose_graph.h"

#include <ceres/ceres.h>

namespace bathyslam {
namespace {

// S with SᵀS = information. Not Cholesky: an edge may leave directions it does not observe at
// zero information, and Cholesky of a singular matrix divides by zero.
Information6 square_root(const Information6& information) {
  const Eigen::SelfAdjointEigenSolver<Information6> eigen(information);
  const Eigen::Matrix<double, 6, 1> roots = eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return roots.asDiagonal() * eigen.eigenvectors().transpose();
}

// Error of a relative-pose measurement between two nodes (position, unit quaternion), whitened
// by the square root of its information. The error is expressed in `from`'s level frame (its
// heading only, z up the true vertical), not its body frame: on flat ground a registration
// observes depth but not where along the bottom it lies, and in a body frame tilted half a
// degree a 20 m error along the bottom would show 0.17 m of it as "depth".
class RelativePoseCost {
 public:
  RelativePoseCost(const Eigen::Isometry3d& measured, const Eigen::Vector3d& anchor,
                   const Information6& sqrt_information)
      : anchor_(anchor),
        anchor_measured_(measured * anchor),
        q_measured_(Eigen::Quaterniond(measured.rotation()).normalized()),
        sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* p_a_ptr, const T* q_a_ptr, const T* p_b_ptr, const T* q_b_ptr,
                  T* residuals_ptr) const {
    Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_a(p_a_ptr), p_b(p_b_ptr);
    Eigen::Map<const Eigen::Quaternion<T>> q_a(q_a_ptr), q_b(q_b_ptr);
    const Eigen::Quaternion<T> q_a_inverse = q_a.conjugate();
    const Eigen::Quaternion<T> q_ab = q_a_inverse * q_b;
    const Eigen::Matrix<T, 3, 1> p_ab = q_a_inverse * (p_b - p_a);
    const Eigen::Quaternion<T> delta_q = q_measured_.template cast<T>() * q_ab.conjugate();

    const Eigen::Quaternion<T> tilt = level_from_body(Eigen::Quaternion<T>(q_a));

    Eigen::Map<Eigen::Matrix<T, 6, 1>> residuals(residuals_ptr);
    residuals.template head<3>() = tilt * (q_ab * anchor_.template cast<T>() + p_ab - anchor_measured_.template cast<T>());
    residuals.template tail<3>() = tilt * (T(2.0) * delta_q.vec());
    residuals.applyOnTheLeft(sqrt_information_.template cast<T>());
    return true;
  }

  static ceres::CostFunction* create(const PoseGraphEdge& edge) {
    const Information6 sqrt_information = square_root(edge.information);
    return new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 3, 4, 3, 4>(
        new RelativePoseCost(edge.measured, edge.anchor, sqrt_information));
  }

 private:
  Eigen::Vector3d anchor_;           // in `to`'s frame
  Eigen::Vector3d anchor_measured_;  // where the measurement puts it in `from`'s frame
  Eigen::Quaterniond q_measured_;
  Information6 sqrt_information_;
};

}  // namespace

Information6 information_from_sigmas(const Eigen::Vector3d& translation_m,
                                     const Eigen::Vector3d& rotation_rad) {
  Eigen::Matrix<double, 6, 1> sigma;
  sigma << translation_m, rotation_rad;
  return sigma.cwiseAbs2().cwiseInverse().asDiagonal();
}

std::vector<PoseGraphEdge> odometry_edges(const std::vector<Eigen::Isometry3d>& dead_reckoning,
                                          const Information6& information) {
  std::vector<PoseGraphEdge> edges;
  for (std::size_t i = 1; i < dead_reckoning.size(); ++i) {
    edges.push_back({static_cast<int>(i - 1), static_cast<int>(i), dead_reckoning[i - 1].inverse() * dead_reckoning[i],
                     information});
  }
  return edges;
}

GraphSolution optimize_pose_graph(const std::vector<Eigen::Isometry3d>& initial,
                                  const std::vector<PoseGraphEdge>& edges, const GraphConfig& config) {
  std::vector<Eigen::Vector3d> positions(initial.size());
  std::vector<Eigen::Quaterniond> rotations(initial.size());
  for (std::size_t i = 0; i < initial.size(); ++i) {
    positions[i] = initial[i].translation();
    rotations[i] = Eigen::Quaterniond(initial[i].rotation()).normalized();
  }

  ceres::Problem problem;
  ceres::Manifold* quaternion_manifold = new ceres::EigenQuaternionManifold;
  for (const PoseGraphEdge& edge : edges) {
    ceres::LossFunction* loss = edge.robust ? new ceres::HuberLoss(config.huber_delta) : nullptr;
    problem.AddResidualBlock(RelativePoseCost::create(edge), loss, positions[edge.from].data(),
                             rotations[edge.from].coeffs().data(), positions[edge.to].data(),
                             rotations[edge.to].coeffs().data());
  }
  for (std::size_t i = 0; i < initial.size(); ++i) {
    if (problem.HasParameterBlock(rotations[i].coeffs().data())) {
      problem.SetManifold(rotations[i].coeffs().data(), quaternion_manifold);
    }
  }
  GraphSolution solution;
  solution.poses = initial;
  if (initial.empty() || !problem.HasParameterBlock(positions[0].data())) {
    delete quaternion_manifold;  // never handed to the problem
    solution.converged = true;
    return solution;
  }
  // The first pose anchors the map: it is shared with the reference (design.md, evaluation).
  problem.SetParameterBlockConstant(positions[0].data());
  problem.SetParameterBlockConstant(rotations[0].coeffs().data());

  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = config.max_iterations;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);

  solution.converged = summary.termination_type == ceres::CONVERGENCE;
  solution.iterations = static_cast<int>(summary.iterations.size());
  solution.initial_cost = summary.initial_cost;
  solution.final_cost = summary.final_cost;
  for (std::size_t i = 0; i < initial.size(); ++i) {
    solution.poses[i] = Eigen::Isometry3d::Identity();
    solution.poses[i].linear() = rotations[i].normalized().toRotationMatrix();
    solution.poses[i].translation() = positions[i];
  }
  return solution;
}

}  // namespace bathyslam
