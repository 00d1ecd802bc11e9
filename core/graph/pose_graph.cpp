#include "core/graph/pose_graph.h"

#include <algorithm>
#include <cmath>

#include <ceres/ceres.h>
#include <ceres/covariance.h>

#include "core/graph/dr_noise.h"
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

namespace {

// The graph as one Ceres problem over `nodes` (each a position and a unit quaternion), node 0 and
// the nodes before `first_free` held. `anchored`: a held node is in an edge, so the map's place is
// fixed and the problem can be solved.
struct GraphProblem {
  ceres::Problem problem;
  std::vector<Node> nodes;
  bool anchored = false;

  GraphProblem(const std::vector<Eigen::Isometry3d>& initial, const std::vector<PoseGraphEdge>& edges,
               const GraphConfig& config, int first_free)
      : nodes(initial.size()) {
    for (std::size_t i = 0; i < initial.size(); ++i) {
      nodes[i].head<3>() = initial[i].translation();
      nodes[i].tail<4>() = Eigen::Quaterniond(initial[i].rotation()).normalized().coeffs();
    }
    ceres::Manifold* node_manifold = new NodeManifold;
    for (const PoseGraphEdge& edge : edges) {
      ceres::LossFunction* loss = edge.robust ? registration_loss(config) : nullptr;
      problem.AddResidualBlock(new RelativePoseCost(edge), loss, nodes[edge.from].data(), nodes[edge.to].data());
    }
    bool handed = false;
    for (Node& node : nodes) {
      if (!problem.HasParameterBlock(node.data())) continue;
      problem.SetManifold(node.data(), node_manifold);
      handed = true;
    }
    if (!handed) delete node_manifold;  // never handed to the problem
    // The first pose anchors the map: it is shared with the reference (docs/design.md,
    // evaluation). With `first_free`, the poses before it anchor it together.
    const int held = std::min<int>(std::max(first_free, 1), static_cast<int>(nodes.size()));
    for (int i = 0; i < held; ++i) {
      if (!problem.HasParameterBlock(nodes[i].data())) continue;
      problem.SetParameterBlockConstant(nodes[i].data());
      anchored = true;
    }
  }

  Eigen::Isometry3d pose(std::size_t i) const {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::Quaterniond(nodes[i].tail<4>()).normalized().toRotationMatrix();
    pose.translation() = nodes[i].head<3>();
    return pose;
  }
};

// d(x, y, yaw of `to` in `from`'s level frame) / d(tangent of `from`, tangent of `to`), each
// tangent a position step and half a rotation vector in map axes (NodeManifold's: Ceres turns a
// quaternion on the left by [cos |δ|, sin |δ| δ/|δ|], a turn of 2|δ|).
Eigen::Matrix<double, 3, 12> relative_xy_yaw_jacobian(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to) {
  const Eigen::Matrix3d level_t = level_frame(from).linear().transpose();
  const Eigen::Vector3d w = level_t * (to.translation() - from.translation());
  Eigen::Matrix<double, 3, 12> j = Eigen::Matrix<double, 3, 12>::Zero();
  j.block<2, 3>(0, 0) = -level_t.topRows<2>();
  j.block<2, 3>(0, 6) = level_t.topRows<2>();
  // Turning `from` by δψ about the vertical turns its level frame, so `to` moves by −δψ ẑ × w in it.
  j(0, 5) = 2 * w.y();
  j(1, 5) = -2 * w.x();
  j(2, 5) = -2;
  j(2, 11) = 2;
  return j;
}

}  // namespace

std::optional<std::vector<Eigen::Matrix3d>> relative_covariances(const std::vector<Eigen::Isometry3d>& poses,
                                                                  const std::vector<PoseGraphEdge>& edges,
                                                                  const GraphConfig& config,
                                                                  const std::vector<std::pair<int, int>>& pairs) {
  GraphProblem graph(poses, edges, config, 1);
  if (!graph.anchored) return std::nullopt;
  std::vector<std::pair<const double*, const double*>> blocks;
  const auto wanted = [&](int a, int b) {
    const double *x = graph.nodes[a].data(), *y = graph.nodes[b].data();
    if (std::find(blocks.begin(), blocks.end(), std::make_pair(x, y)) == blocks.end() &&
        std::find(blocks.begin(), blocks.end(), std::make_pair(y, x)) == blocks.end())
      blocks.emplace_back(x, y);
  };
  for (const auto& [a, b] : pairs) {
    if (!graph.problem.HasParameterBlock(graph.nodes[a].data()) || !graph.problem.HasParameterBlock(graph.nodes[b].data()))
      return std::nullopt;
    wanted(a, a), wanted(b, b), wanted(a, b);
  }
  ceres::Covariance::Options options;
  options.algorithm_type = ceres::SPARSE_QR;
  options.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
  options.num_threads = 1;
  ceres::Covariance covariance(options);
  if (!covariance.Compute(blocks, &graph.problem)) return std::nullopt;
  std::vector<Eigen::Matrix3d> out;
  out.reserve(pairs.size());
  for (const auto& [a, b] : pairs) {
    // Tangent blocks of the two nodes, joint: [aa ab; ba bb]; a held node's are zero.
    Eigen::Matrix<double, 12, 12> joint = Eigen::Matrix<double, 12, 12>::Zero();
    Eigen::Matrix<double, 6, 6, Eigen::RowMajor> block;
    const double *x = graph.nodes[a].data(), *y = graph.nodes[b].data();
    covariance.GetCovarianceBlockInTangentSpace(x, x, block.data());
    joint.topLeftCorner<6, 6>() = block;
    covariance.GetCovarianceBlockInTangentSpace(y, y, block.data());
    joint.bottomRightCorner<6, 6>() = block;
    covariance.GetCovarianceBlockInTangentSpace(x, y, block.data());
    joint.topRightCorner<6, 6>() = block;
    joint.bottomLeftCorner<6, 6>() = block.transpose();
    const Eigen::Matrix<double, 3, 12> j = relative_xy_yaw_jacobian(poses[a], poses[b]);
    out.push_back(j * joint * j.transpose());
  }
  return out;
}

GraphSolution optimize_pose_graph(const std::vector<Eigen::Isometry3d>& initial,
                                  const std::vector<PoseGraphEdge>& edges, const GraphConfig& config, int first_free) {
  GraphProblem graph(initial, edges, config, first_free);
  GraphSolution solution;
  solution.poses = initial;
  if (!graph.anchored) {
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
  ceres::Solve(options, &graph.problem, &summary);

  solution.converged = summary.termination_type == ceres::CONVERGENCE;
  solution.iterations = static_cast<int>(summary.iterations.size());
  solution.initial_cost = summary.initial_cost;
  solution.final_cost = summary.final_cost;
  for (std::size_t i = 0; i < initial.size(); ++i) solution.poses[i] = graph.pose(i);
  return solution;
}

}  // namespace bathyslam
