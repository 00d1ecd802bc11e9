#pragma once
// register: what a registration observed. The GICP cost's Gauss–Newton Hessian at the solution
// says which directions the overlap pins down (a flat bottom: depth, roll, pitch; sand waves:
// also across their crests) and which it leaves free; the edge information keeps that shape and
// takes its scale from the quality weight (docs/slam-core.md, "Quality-aware information").
#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/graph/pose_graph.h"
#include "core/register/gicp.h"

namespace bathyslam {

using Matrix6 = Eigen::Matrix<double, 6, 6>;

// One GICP correspondence: a source point (source frame), its nearest target point (target
// frame) and their plane-regularised covariances, each in its own cloud's frame.
struct GicpTerm {
  Eigen::Vector3d source = Eigen::Vector3d::Zero();
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Matrix3d source_covariance = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d target_covariance = Eigen::Matrix3d::Identity();
};

// The correspondences GICP would use at `source_to_target`: every source point's nearest target
// point within `config.max_correspondence_m`, with covariances from `config.neighbours` nearest
// neighbours regularised to a plane (eigenvalues 1, 1, 1e-3; Segal et al. 2009).
std::vector<GicpTerm> gicp_terms(const Cloud& target, const Cloud& source, const Eigen::Isometry3d& source_to_target,
                                 const GicpConfig& config);

// ½ Σ dᵀ (C_t + R C_s Rᵀ)⁻¹ d with d = R p_s + t - p_t: the GICP cost over fixed correspondences.
double gicp_cost(const std::vector<GicpTerm>& terms, const Eigen::Isometry3d& source_to_target);

struct GicpHessian {
  // Σ Jᵀ M J, M = (C_t + R C_s Rᵀ)⁻¹, for a perturbation (translation of the anchor, then a
  // rotation vector about it), both in the target frame: the pose graph's anchored edge.
  Matrix6 hessian = Matrix6::Zero();
  // Σ Jᵀ (½ I) J: the part of `hessian` that the regularisation gives every correspondence in
  // every direction whatever the terrain. Each covariance has eigenvalues at most 1, so M ≥ ½ I:
  // even two points on a flat bottom "pull" each other along it, which the next nearest-
  // neighbour search would undo. `hessian - regularisation` is what the overlap observed.
  Matrix6 regularisation = Matrix6::Zero();
  std::size_t correspondences = 0;
};

GicpHessian gicp_hessian(const std::vector<GicpTerm>& terms, const Eigen::Isometry3d& source_to_target,
                         const Eigen::Vector3d& anchor_in_source);

// The above on freshly found correspondences (gicp_terms).
GicpHessian gicp_hessian(const Cloud& target, const Cloud& source, const Eigen::Isometry3d& source_to_target,
                         const Eigen::Vector3d& anchor_in_source, const GicpConfig& config);

// `hessian` for a perturbation expressed in a frame turned by `rotation` from the original one
// (translation and rotation vector alike turn with it).
GicpHessian rotated(const GicpHessian& hessian, const Eigen::Matrix3d& rotation);

// Edge information from what a registration observed. `hessian` (in the edge's residual
// frame) gives the shape: which directions the overlap pins down, and how well relative to the
// best-pinned one. Its scale is meaningless (every point counts as an independent observation),
// so the scale comes from the quality weight: no direction gets more than `quality_weight` times
// the information of `best_sigmas` (x, y, z m; roll, pitch, yaw rad), and a textured overlap
// gets just that.
//
// Directions are compared on `hessian - regularisation` (what the terrain observed) whitened by
// shape_scales, eigenvalue by eigenvalue as shares of the largest. A share of `full_share` or
// more counts as fully observed: seabed slopes are gentle, so even well-textured ground gives
// GICP some 20 times less horizontal than vertical curvature (mounds: 3 to 8 %,
// registration_information_test.cpp), yet the best sigmas hold a textured registration to
// 0.1 m. Below that a direction keeps a proportional part, and below `zero_share` none: the
// noise of the soundings tilts each point's normal and so fakes horizontal curvature on a flat
// bottom (up to ~1 % at 0.1 m noise on a 0.25 m grid).
Information6 observed_information(const GicpHessian& hessian, double quality_weight,
                                  const Eigen::Matrix<double, 6, 1>& best_sigmas, double full_share,
                                  double zero_share);

// The units observed_information compares directions in. Translations: the best sigmas, so
// that depth (0.05 m) is not outweighed by the horizontal (0.1 m). Rotations: the displacement
// they cause at the overlap, in the same units: roll and pitch tilt it, moving its points
// vertically by the angle times their lever (compared with the depth sigma), yaw turns it,
// moving them horizontally (compared with the horizontal sigma). The levers are the RMS
// distances of the source points from each axis through the anchor. Whitening rotations by
// their own best sigmas instead would imply a 25 to 50 m lever (0.1 m / 0.004 rad, 0.05 m /
// 0.002 rad): a 20 m overlap would see its roll and yaw as a few percent of its depth even on a
// textured or flat bottom, and size is already in the quality weight (overlap points).
Eigen::Matrix<double, 6, 1> shape_scales(const GicpHessian& hessian, const Eigen::Matrix<double, 6, 1>& best_sigmas);

}  // namespace bathyslam
