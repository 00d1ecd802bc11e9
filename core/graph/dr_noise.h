#pragma once
// dr_noise: how far dead reckoning may have drifted between two nodes, and whether a measured
// relative pose is one DR could have come to.
//
// Every relative pose and covariance here uses one parametrisation, that of RelativePoseCost
// (relative_pose_error.h): between the level frames of the two nodes (heading only, z the true
// vertical), a perturbed pose is (exp(δθ)·R, t + δt) with δt and δθ in `from`'s level frame,
// ordered δt x, y, z then δθ about x, y, z (yaw last).
#include <map>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "core/graph/pose_graph.h"

namespace bathyslam {

using Vector6 = Eigen::Matrix<double, 6, 1>;
using Covariance6 = Eigen::Matrix<double, 6, 6>;

// [v]ₓ: [v]ₓ·w = v × w.
Eigen::Matrix3d skew(const Eigen::Vector3d& v);

// `pose` with its roll and pitch taken out: the same position, its heading only.
Eigen::Isometry3d level_frame(const Eigen::Isometry3d& pose);

// `relative` (the pose of node `to` in node `from`'s body frame) as a pose between the nodes'
// level frames, the nodes standing at `from_pose` and `to_pose` (their DR poses will do).
Eigen::Isometry3d between_level_frames(const Eigen::Isometry3d& relative, const Eigen::Isometry3d& from_pose,
                                       const Eigen::Isometry3d& to_pose);

// The noise DR accumulates along the chain of odometry steps between two nodes, each step with
// independent noise of GraphConfig's DR sigmas (translation in the step's level frame, rotation),
// propagated to first order: a heading error at a step turns everything after it about the node
// it leads to, so a later position moves sideways by its distance from there times the angle.
// Prefix sums make a query O(1) after an O(n) construction. With several surveys
// (GraphConfig::survey_starts) the steps form a tree: each survey's chain hangs off node 0 by its
// datum edge, and two surveys' nodes are joined through their starts and the datum.
class DrNoiseModel {
 public:
  DrNoiseModel(const std::vector<Eigen::Isometry3d>& dead_reckoning, const GraphConfig& config);

  int size() const { return static_cast<int>(level_.size()); }
  // DR's pose of `to` in `from`'s level frame (level frames at both ends).
  Eigen::Isometry3d relative_pose(int from, int to) const;
  // Covariance of relative_pose(from, to); either order, from == to gives zero.
  Covariance6 covariance(int from, int to) const;

 private:
  // Of a set of steps (step m joins node m to m + 1, its rotation turning everything beyond about
  // node m + 1 at s_m): Σ Qt, Σ Qr, Σ [s]ₓQr, Σ [s]ₓQr[s]ₓᵀ, Qt and Qr the step's translation and
  // rotation covariances in map axes.
  struct StepSums {
    Eigen::Matrix3d qt = Eigen::Matrix3d::Zero(), qr = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d s_qr = Eigen::Matrix3d::Zero(), s_qr_s = Eigen::Matrix3d::Zero();
    void add(const Eigen::Matrix3d& step_qt, const Eigen::Matrix3d& step_qr, const Eigen::Matrix3d& s);
    StepSums& operator+=(const StepSums& other);
    StepSums operator-(const StepSums& other) const;
  };
  // The steps from node `node`'s survey start to it, and that start's datum edge.
  StepSums path_from_datum(int node) const;

  std::vector<Eigen::Isometry3d> level_;  // DR poses, level frames
  Eigen::Vector3d origin_;                // positions are taken from here, to keep the sums small
  std::vector<StepSums> prefix_;          // over steps m < k
  std::vector<int> start_of_;             // each node's survey start (0 for the first survey)
  std::map<int, StepSums> datum_;         // each later survey start's datum edge
};

// The same for one query, building the model: O(n).
Covariance6 dr_relative_covariance(const std::vector<Eigen::Isometry3d>& dead_reckoning, int from, int to,
                                   const GraphConfig& config);

// The inverse of `information`, with `unobserved_variance` (m² or rad²) along the directions it
// leaves (near) zero: large enough to say nothing, finite so sums of covariances stay invertible.
Covariance6 covariance_from_information(const Information6& information, double unobserved_variance = 1e4);

// A measurement's error covariance in this parametrisation, from the information of its edge.
// Directions the information leaves (near) zero get `unobserved_variance`. RelativePoseCost's error
// is estimate − measurement in translation and measurement − estimate in rotation, which flips
// the sign of translation–rotation cross terms, and it compares translation at the edge's anchor:
// both are converted here, to the pose of `to`'s origin. `from_pose` gives `from`'s tilt.
Covariance6 measurement_covariance(const PoseGraphEdge& edge, const Eigen::Isometry3d& from_pose,
                                   double unobserved_variance = 1e4);

// measured − predicted: translation difference and the rotation vector of measured·predicted⁻¹,
// in the frame both are expressed in. The rotation vector's angle is at most π, so yaw lies in
// [−π, π]: 180° is as wrong as a heading can be and 200° counts as −160°.
Vector6 pose_difference(const Eigen::Isometry3d& measured, const Eigen::Isometry3d& predicted);

// Squared Mahalanobis distance of x, y and yaw of `difference` under the marginal of
// `covariance` on them (depth, roll and pitch left out, not conditioned on).
double mahalanobis2_xy_yaw(const Vector6& difference, const Covariance6& covariance);

struct PlausibilityConfig {
  // χ²₃ at 99.9 %: one correct registration in a thousand is refused, a price worth paying when
  // the refused ones are 80°–176° turns or tens of metres off. Only x, y and yaw are tested: DR
  // keeps depth, roll and pitch well and the sonar measures depth, so a registration that
  // corrects them is not suspect.
  double chi2_threshold = 16.27;
  template <typename Field>
  void fields(Field&& field) {
    field("chi2_threshold", chi2_threshold, 0.01, 1e6);
  }
};

struct PlausibilityTest {
  double mahalanobis2 = 0;
  int dof = 3;
  bool plausible = false;
};

// Could DR have come to `measured`? Both poses are of `to` in `from`'s level frame
// (between_level_frames); `covariance` is that of their difference: DR's over the chain plus
// the measurement's.
PlausibilityTest plausibility(const Eigen::Isometry3d& measured, const Eigen::Isometry3d& dr_predicted,
                              const Covariance6& covariance,
                              double chi2_threshold = PlausibilityConfig{}.chi2_threshold);

}  // namespace bathyslam
