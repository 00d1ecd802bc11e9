#pragma once
// register (own GICP), solver: Gauss–Newton on SE(3) over the GICP factors (gicp_factor.h),
// re-associating every iteration, with PCL's GICP's parameters and convergence rule, on submaps
// prepared once (gicp_cloud.h). Returns what register_gicp (the PCL wrapper) returns and, if
// asked, the cost's Hessian at the answer.
#include <atomic>

#include <Eigen/Geometry>

#include "core/register/gicp.h"
#include "core/register/gicp_cloud.h"
#include "core/register/gicp_factor.h"
#include "core/register/registration_information.h"

namespace bathyslam {

// PCL's GICP rotation epsilon (its default, which the wrapper keeps): an iteration that changes
// no rotation-matrix entry by this much and no translation by `convergence` has converged.
constexpr double kGicpRotationEpsilon = 2e-3;
// How much a pass's mean cost must fall over GicpConfig::stall_iterations to go on.
constexpr double kStallShare = 0.01;

struct GaussNewtonPass {
  Eigen::Isometry3d source_to_target = Eigen::Isometry3d::Identity();
  bool converged = false;
  int iterations = 0;
};

// One pass from `start`, associating with `associator` (its gate). Directions the terrain
// observes less than `min_observed_share` of the best-observed one keep their value
// (gicp_solver.cpp, observed_step). The rotation turns about `pivot` (target frame) and the convergence
// rule compares the transform between the frames centred there and at `source_pivot` (source
// frame), which is what PCL sees when the wrapper shifts the clouds (about_centroid). As in PCL,
// reaching `max_iterations` counts as converged, and so does a cost that has not fallen by
// kStallShare over `stall_iterations` (0: never); too few correspondences or a singular system
// does not, nor does turning by more than `max_turn_rad` from `start`, nor a `cancel` set.
GaussNewtonPass gauss_newton_gicp(const GicpCloud& target, const GicpCloud& source, Associator& associator,
                                  const Eigen::Isometry3d& start, const Eigen::Vector3d& pivot,
                                  const Eigen::Vector3d& source_pivot, double convergence, int max_iterations,
                                  int stall_iterations,
                                  double min_observed_share, double max_turn_rad, int threads,
                                  const std::atomic<bool>* cancel = nullptr);

struct PreparedRegistration {
  Registration registration;
  // Of the cost at the answer (Table 1 gate), about `hessian_anchor` (source frame): filled only
  // if asked for.
  GicpHessian hessian;
};

// register_gicp's contract (Table 1 pass, optional about-centroid and refinement pass, quality
// at max_correspondence_m) on the overlap `overlap` of two prepared submaps.
PreparedRegistration register_prepared(const GicpCloud& target, const GicpCloud& source, const GicpOverlap& overlap,
                                       const Eigen::Isometry3d& guess, const GicpConfig& config,
                                       const Eigen::Vector3d* hessian_anchor = nullptr,
                                       const std::atomic<bool>* cancel = nullptr);

// Mean of the soundings the overlap's source sample stands for, source frame (double sum).
Eigen::Vector3d source_centroid(const GicpCloud& source, const GicpOverlap& overlap);

}  // namespace bathyslam
