#include "core/graph/pose_graph.h"

#include <algorithm>
#include <cmath>

#include <ceres/ceres.h>

#include "core/graph/relative_pose_cost.h"
#include "core/graph/relative_pose_error.h"
#include "core/graph/robust_kernel.h"

namespace bathyslam {
namespace {

// A node as one parameter block: position, then the unit quaternion as Eigen stores it (x, y, z,
// w). One block per pose rather than two keeps the normal equations in whole 6x6 blocks, which
// the sparse Cholesky orders and factors faster (bench_regraph on `large`'s final graph:
// docs/performance.md).
constexpr int kNodeSize = 7;
using Node = Eigen::Matrix<double, kNodeSize, 1>;
using NodeManifold = ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold>;

}  // namespace

Eigen::Matrix<double, 6, 1> edge_error(const PoseGraphEdge& edge, const Eigen::Isometry3d& from,
                                       const Eigen::Isometry3d& to) {
  const Eigen::Vector3d p_a = from.translation(), p_b = to.translation();
  const Eigen::Quaterniond q_a(from.rotation()), q_b(to.rotation());
  return relative_pose_error<double>(p_a, q_a.normalized(), p_b, q_b.normalized(), edge.anchor,
                                     edge.measured * edge.anchor,
                                     Eigen::Quaterniond(edge.measured.rotation()).normalized());
}

Eigen::Matrix<double, 6, 1> whitened_residual(const PoseGraphEdge& edge, const Eigen::Isometry3d& from,
                                              const Eigen::Isometry3d& to) {
  return square_root(edge.information) * edge_error(edge, from, to);
}

Information6 information_from_sigmas(const Eigen::Vector3d& translation_m,
                                     const Eigen::Vector3d& rotation_rad) {
  Eigen::Matrix<double, 6, 1> sigma;
  sigma << translation_m, rotation_rad;
  return sigma.cwiseAbs2().cwiseInverse().asDiagonal();
}

Information6 odometry_information(const GraphConfig& config, int k) {
  return information_from_sigmas(config.dr_sigma_translation_m, config.rotation_sigma_of_step(k));
}

bool GraphConfig::has_step(int k) const { return same_survey(k, k + 1); }

bool GraphConfig::same_survey(int a, int b) const { return survey_of(survey_starts, a) == survey_of(survey_starts, b); }

Information6 datum_information(const GraphConfig& config) {
  return information_from_sigmas(std::sqrt(2.0) * config.start_sigma_translation_m,
                                 std::sqrt(2.0) * config.start_sigma_rotation_rad);
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
                                  const std::vector<PoseGraphEdge>& edges, const GraphConfig& config, int first_free) {
  std::vector<Node> nodes(initial.size());
  for (std::size_t i = 0; i < initial.size(); ++i) {
    nodes[i].head<3>() = initial[i].translation();
    nodes[i].tail<4>() = Eigen::Quaterniond(initial[i].rotation()).normalized().coeffs();
  }

  ceres::Problem problem;
  ceres::Manifold* node_manifold = new NodeManifold;
  for (const PoseGraphEdge& edge : edges) {
    ceres::LossFunction* loss = edge.robust ? registration_loss(config) : nullptr;
    problem.AddResidualBlock(new RelativePoseCost(edge), loss, nodes[edge.from].data(), nodes[edge.to].data());
  }
  for (Node& node : nodes) {
    if (problem.HasParameterBlock(node.data())) problem.SetManifold(node.data(), node_manifold);
  }
  GraphSolution solution;
  solution.poses = initial;
  // The first pose anchors the map: it is shared with the reference (docs/design.md, evaluation).
  // With `first_free`, the poses before it anchor it together.
  bool anchored = false;
  const int held = std::min<int>(std::max(first_free, 1), static_cast<int>(nodes.size()));
  for (int i = 0; i < held; ++i) {
    if (!problem.HasParameterBlock(nodes[i].data())) continue;
    problem.SetParameterBlockConstant(nodes[i].data());
    anchored = true;
  }
  if (!anchored) {
    if (problem.NumParameterBlocks() == 0) delete node_manifold;  // never handed to the problem
    solution.converged = true;
    return solution;
  }

  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  // Eigen's sparse Cholesky factors these graphs in about half SuiteSparse's time, to the same
  // cost (bench_regraph on `large`'s final graph: docs/performance.md).
  options.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
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
    solution.poses[i].linear() = Eigen::Quaterniond(nodes[i].tail<4>()).normalized().toRotationMatrix();
    solution.poses[i].translation() = nodes[i].head<3>();
  }
  return solution;
}

}  // namespace bathyslam
