#pragma once
// graph: the pose graph over submap poses, solved with Ceres (as Ceres' pose_graph_3d example).
#include <map>
#include <optional>
#include <vector>

#include <Eigen/Geometry>
#include "core/types/fields.h"
#include "core/types/survey_starts.h"

namespace bathyslam {

using Information6 = Eigen::Matrix<double, 6, 6>;

// A relative-pose constraint: `measured` is the pose of node `to` in the frame of node `from`.
// Residual order: translation x, y, z (from's frame, at `anchor`), then rotation about x, y, z (roll, pitch,
// yaw for a vehicle frame).
struct PoseGraphEdge {
  int from = 0;
  int to = 0;
  Eigen::Isometry3d measured = Eigen::Isometry3d::Identity();
  Information6 information = Information6::Identity();
  bool robust = false;  // GraphConfig's robust kernel (registrations); odometry edges are trusted as Gaussian
  // The point of `to`'s frame (its own coordinates) where the translation is compared: a
  // registration pins down where the overlap lands far better than where `to`'s origin, tens of
  // metres away, lands; comparing at the overlap keeps a loose yaw from posing as a translation.
  // Zero compares origins.
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
};

// The rotation taking a node's body-frame vectors to its level frame (the same heading, z up the
// true vertical), in which an edge's residual is taken. `body_to_map`: the node's rotation.
template <typename T>
Eigen::Quaternion<T> level_from_body(const Eigen::Quaternion<T>& body_to_map) {
  using std::atan2;
  const Eigen::Quaternion<T>& q = body_to_map;
  const T yaw = atan2(T(2) * (q.w() * q.z() + q.x() * q.y()), T(1) - T(2) * (q.y() * q.y() + q.z() * q.z()));
  return Eigen::Quaternion<T>(Eigen::AngleAxis<T>(-yaw, Eigen::Matrix<T, 3, 1>::UnitZ())) * q;
}

// The x, y and yaw rows and columns of a 6x6 information or covariance in the edge's order: what
// bends a survey sideways or turns it, and what the DR gate, PCM and the safety net test.
inline Eigen::Matrix3d xy_yaw_block(const Information6& m) {
  constexpr int axes[3] = {0, 1, 5};
  Eigen::Matrix3d block;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) block(i, j) = m(axes[i], axes[j]);
  }
  return block;
}

// Diagonal information from standard deviations (metres, radians).
Information6 information_from_sigmas(const Eigen::Vector3d& translation_m,
                                     const Eigen::Vector3d& rotation_rad);

// Edges between consecutive nodes carrying the relative pose dead reckoning gives (Table 1's
// odometry constraints when `information` is the DR information).
std::vector<PoseGraphEdge> odometry_edges(const std::vector<Eigen::Isometry3d>& dead_reckoning,
                                          const Information6& information);

// The loss on robust (registration) edges.
enum class RobustKernel {
  huber,  // a wrong edge keeps pulling, linearly in its error
  dcs,    // dynamic covariance scaling: a wrong edge's pull fades as its error grows (robust_kernel.h)
};

struct GraphConfig {
  // Table 1 (c): DR noise, translation (5, 5, 1) m and rotation (1e-4, 1e-4, 1e-2) rad.
  Eigen::Vector3d dr_sigma_translation_m{5.0, 5.0, 1.0};
  Eigen::Vector3d dr_sigma_rotation_rad{1e-4, 1e-4, 1e-2};
  // Odometry steps (node k to k + 1, by k) whose heading jumped, each with its own yaw sigma: a
  // compass step is one large error among small ones, which no single sigma describes
  // (navigation_noise.h finds them). Not a --set field.
  std::map<int, double> step_yaw_sigma_rad;
  // The DR sigmas of rotation of the step from node k.
  Eigen::Vector3d rotation_sigma_of_step(int k) const {
    const auto jump = step_yaw_sigma_rad.find(k);
    return jump == step_yaw_sigma_rad.end() ? dr_sigma_rotation_rad
                                            : Eigen::Vector3d(dr_sigma_rotation_rad.x(), dr_sigma_rotation_rad.y(), jump->second);
  }
  // Several surveys of one site in one graph: the first node of each survey after the first.
  // No odometry step leads into one; each hangs off node 0, the first survey's first pose (the
  // datum), by a datum edge whose noise is both surveys' start fixes (a GPS fix before the dive).
  // Empty: one survey. Not a --set field: the job's surveys give it.
  std::vector<int> survey_starts;
  // A survey's start fix: where its dead reckoning began, as the vehicle knew it (x, y, depth;
  // roll, pitch, heading). A surface GPS fix is good to a few metres; the heading is the INS's.
  Eigen::Vector3d start_sigma_translation_m{3.0, 3.0, 0.5};
  Eigen::Vector3d start_sigma_rotation_rad{1e-3, 1e-3, 0.02};
  // Whether an odometry step leads from node k to k + 1 (not into another survey's start).
  bool has_step(int k) const;
  bool same_survey(int a, int b) const;
  RobustKernel robust_kernel = RobustKernel::huber;
  double huber_delta = 1.0;  // on whitened residuals
  // DCS's Φ, on the squared whitened residual: below it an edge keeps its full weight. χ²₆ at
  // 95 %, so a correct registration whose information is honest is left alone; Agarwal et al.'s
  // Φ = 1 would already scale the typical correct edge (χ² ≈ 6) to a twelfth of its weight.
  double dcs_phi = 12.59;
  int max_iterations = 200;
  template <typename Field>
  void fields(Field&& field) {
    xyz("dr_sigma_translation_m", dr_sigma_translation_m, 1e-4, 1e3, field);
    rpy("dr_sigma_rotation_rad", dr_sigma_rotation_rad, 1e-8, 10, field);
    xyz("start_sigma_translation_m", start_sigma_translation_m, 1e-4, 1e4, field);
    rpy("start_sigma_rotation_rad", start_sigma_rotation_rad, 1e-8, 10, field);
    field("robust_kernel", robust_kernel, 0, 1);  // 0 huber, 1 dcs
    field("huber_delta", huber_delta, 1e-3, 1e3);
    field("dcs_phi", dcs_phi, 1e-3, 1e6);
    field("max_iterations", max_iterations, 1, 10000);
  }
};

// The information of the odometry step from node `k` under `config`'s DR sigmas.
Information6 odometry_information(const GraphConfig& config, int k);

// The information of a datum edge (node 0 to another survey's first node): the two start fixes'
// noise, independent, added.
Information6 datum_information(const GraphConfig& config);

struct GraphSolution {
  std::vector<Eigen::Isometry3d> poses;
  bool converged = false;
  int iterations = 0;
  double initial_cost = 0;
  double final_cost = 0;
};

// The error of `edge` at node poses `from` and `to` (relative_pose_error.h: translation at the
// anchor and rotation, in `from`'s level frame), unwhitened and whitened by its information.
Eigen::Matrix<double, 6, 1> edge_error(const PoseGraphEdge& edge, const Eigen::Isometry3d& from,
                                       const Eigen::Isometry3d& to);
Eigen::Matrix<double, 6, 1> whitened_residual(const PoseGraphEdge& edge, const Eigen::Isometry3d& from,
                                              const Eigen::Isometry3d& to);

// Optimises `initial` (node poses in the map frame) under `edges`, with node 0 held fixed, and
// every node before `first_free` too. Nothing moves when none of the held nodes is in an edge
// (nothing would fix the map's place).
GraphSolution optimize_pose_graph(const std::vector<Eigen::Isometry3d>& initial,
                                  const std::vector<PoseGraphEdge>& edges, const GraphConfig& config = {},
                                  int first_free = 1);

// How well the graph `edges` at `poses` (node 0 held) fixes where node `to` lies in node `from`'s
// level frame: the first-order covariance of x, y (m) and yaw (rad) there, the parametrisation of
// DrNoiseModel (dr_noise.h), one matrix per pair of `pairs`. Dead reckoning's covariance is that of
// the odometry alone; every registration the graph holds can only shrink it. nullopt when the
// graph does not determine it (a node in no edge, or Ceres finds the graph rank-deficient).
std::optional<std::vector<Eigen::Matrix3d>> relative_covariances(const std::vector<Eigen::Isometry3d>& poses,
                                                                  const std::vector<PoseGraphEdge>& edges,
                                                                  const GraphConfig& config,
                                                                  const std::vector<std::pair<int, int>>& pairs);

}  // namespace bathyslam
