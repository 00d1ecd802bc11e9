#include "core/register/gicp_solver.h"

#include <algorithm>

#include <Eigen/Dense>

#include "core/register/anderson.h"

namespace bathyslam {
namespace {

constexpr double kFloatResolutionM = 1e-5;
// Answers Anderson mixes: a handful, as AA-ICP found enough.
constexpr int kAndersonDepth = 5;

// x' = exp(δθ)(x - c) + c + δt: the perturbation the factors are linearised for.
Eigen::Isometry3d perturbed(const Eigen::Isometry3d& t, const Vector6d& step, const Eigen::Vector3d& pivot) {
  Eigen::Isometry3d move = Eigen::Isometry3d::Identity();
  const double angle = step.tail<3>().norm();
  if (angle > 0) move.linear() = Eigen::AngleAxisd(angle, step.tail<3>() / angle).toRotationMatrix();
  move.translation() = pivot - move.linear() * pivot + step.head<3>();
  Eigen::Isometry3d out = move * t;
  // Keep the rotation a rotation over hundreds of products.
  out.linear() = Eigen::Quaterniond(out.rotation()).normalized().toRotationMatrix();
  return out;
}

// PCL's rule: the largest change of a rotation-matrix entry over the rotation epsilon, or of a
// translation over the transformation epsilon, below 1.
// The Gauss–Newton step restricted to the directions the terrain observes. Each plane
// covariance leaves every correspondence a pull of ½ I along the seabed (Σ Jᵀ ½ J, the
// regularisation), so on a flat bottom the full step slides along it and turns in yaw, on
// nothing but the nearest-neighbour pattern of the soundings, wherever the guess started (PCL's
// BFGS stalls there instead, near its guess). What the terrain observes is the rest, Σ Jᵀ (M - ½ I) J,
// compared with rotations in metres at the overlap (their RMS lever, as shape_scales does): its
// directions below `min_share` of the best-observed one keep their guess ("solution remapping",
// Zhang et al. 2016); the step is the minimiser over the others.
Vector6d observed_step(const GicpLinearisation& lin, double min_share) {
  // A whisker of damping (small_gicp's 1e-6) keeps an exactly singular system solvable.
  if (min_share <= 0) return -(lin.hessian + 1e-6 * Matrix6d::Identity()).ldlt().solve(lin.gradient);
  const Vector6d d = lin.regularisation.diagonal();
  Vector6d scale = Vector6d::Ones();
  for (int k = 0; k < 3; ++k) scale(3 + k) = 1.0 / std::max(std::sqrt(d(3 + k) / std::max(d(k), 1e-300)), 1e-9);
  const Matrix6d observed = scale.asDiagonal() * (lin.hessian - lin.regularisation) * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eigen(0.5 * (observed + observed.transpose()));
  const double strongest = eigen.eigenvalues().maxCoeff();
  int kept = 0;
  Eigen::Matrix<double, 6, 6> basis;
  for (int k = 0; k < 6; ++k) {
    if (strongest > 0 && eigen.eigenvalues()(k) >= min_share * strongest) basis.col(kept++) = eigen.eigenvectors().col(k);
  }
  if (kept == 0) return Vector6d::Zero();
  const Eigen::MatrixXd v = scale.asDiagonal() * basis.leftCols(kept);  // whitened directions as steps
  const Eigen::MatrixXd reduced = v.transpose() * lin.hessian * v + 1e-6 * Eigen::MatrixXd::Identity(kept, kept);
  return v * reduced.ldlt().solve(-v.transpose() * lin.gradient);
}

// The coordinates of `t` as a perturbation of `start` about `pivot` (perturbed), rotations in
// metres at `lever_m`, and back: where Anderson mixes the answers.
Vector6d coordinates(const Eigen::Isometry3d& t, const Eigen::Isometry3d& start, const Eigen::Vector3d& pivot,
                     double lever_m) {
  const Eigen::Isometry3d move = t * start.inverse();
  const Eigen::AngleAxisd rotation(move.linear());
  Vector6d v;
  v << move.translation() - pivot + move.linear() * pivot, lever_m * rotation.angle() * rotation.axis();
  return v;
}

Eigen::Isometry3d pose_at(const Vector6d& v, const Eigen::Isometry3d& start, const Eigen::Vector3d& pivot,
                          double lever_m) {
  Vector6d step;
  step << v.head<3>(), v.tail<3>() / lever_m;
  return perturbed(start, step, pivot);
}

// RMS distance of the associated source points from the pivot at `t`: how far a rotation moves them.
double rms_lever(const GicpCloud& source, const std::vector<GicpCorrespondence>& correspondences,
                 const Eigen::Isometry3d& t, const Eigen::Vector3d& pivot) {
  double sum = 0;
  for (const GicpCorrespondence& c : correspondences) sum += (t * source.points[c.source].cast<double>() - pivot).squaredNorm();
  return correspondences.empty() ? 1.0 : std::max(std::sqrt(sum / static_cast<double>(correspondences.size())), 1.0);
}

bool small_change(const Eigen::Isometry3d& before, const Eigen::Isometry3d& after, double convergence,
                  double rotation_share = 1.0) {
  const double rotation = (after.linear() - before.linear()).cwiseAbs().maxCoeff() / (rotation_share * kGicpRotationEpsilon);
  const double translation = (after.translation() - before.translation()).cwiseAbs().maxCoeff() / convergence;
  return std::max(rotation, translation) < 1;
}

// Of the soundings the overlap's sample points stand for (GicpCloud::represents).
Eigen::Vector3d target_centroid(const GicpCloud& target, const GicpOverlap& overlap) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double n = 0;
  for (std::size_t j = 0; j < target.points.size(); ++j) {
    if (overlap.target_allowed.empty() || overlap.target_allowed[j]) {
      sum += target.represents[j] * target.points[j].cast<double>();
      n += target.represents[j];
    }
  }
  return n > 0 ? Eigen::Vector3d(sum / n) : sum;
}

}  // namespace

Eigen::Vector3d source_centroid(const GicpCloud& source, const GicpOverlap& overlap) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double n = 0;
  for (uint32_t i : overlap.source_points) {
    sum += source.represents[i] * source.points[i].cast<double>();
    n += source.represents[i];
  }
  return n > 0 ? Eigen::Vector3d(sum / n) : sum;
}

GaussNewtonPass gauss_newton_gicp(const GicpCloud& target, const GicpCloud& source, Associator& associator,
                                  const Eigen::Isometry3d& start, const Eigen::Vector3d& pivot,
                                  const Eigen::Vector3d& source_pivot, double convergence, int max_iterations,
                                  int stall_iterations, double min_observed_share, double max_turn_rad, int threads,
                                  const std::atomic<bool>* cancel) {
  const Eigen::Translation3d to_pivot(-pivot), from_source_pivot(source_pivot);
  auto centred = [&](const Eigen::Isometry3d& t) { return Eigen::Isometry3d(to_pivot * t * from_source_pivot); };
  // Float soundings cannot tell apart poses closer than their resolution (a float 100 m from
  // the origin resolves 8 µm): PCL, whose transforms are float too, stops there whatever the
  // epsilon; a double pose would go on creeping by microns as single associations flip.
  convergence = std::max(convergence, kFloatResolutionM);
  GaussNewtonPass pass;
  pass.source_to_target = start;
  std::vector<Eigen::Isometry3d> answers{centred(start)};  // to see a cycle
  AndersonAcceleration anderson(kAndersonDepth);
  Eigen::Isometry3d at = start;        // where the next association is made
  bool accelerated = false;            // `at` is Anderson's mix, not the last answer
  double last_cost = INFINITY;         // mean cost per correspondence at the last point kept
  double stall_cost = INFINITY;        // the cost to beat by kStallShare, and when it was set
  int stall_since = 0;
  double lever_m = 0;                  // rotations in metres at the overlap, for Anderson's mix
  while (pass.iterations < max_iterations) {
    if (cancel != nullptr && cancel->load()) return pass;  // the job is stopping: its results go
    // As PCL: associate, then minimise over those correspondences (PCL: BFGS, at most 20 inner
    // iterations; here one Gauss–Newton step, as AA-ICP takes: more steps on the same
    // correspondences cost a linearisation each and, with Anderson's mix, no iterations), then
    // compare with the last answer. An association that no longer changes then gives the same
    // answer, and the rule ends the pass.
    const std::vector<GicpCorrespondence> correspondences = associator.at(at, threads);
    ++pass.iterations;
    // PCL's BFGS refuses fewer than 4 correspondences and the registration then fails.
    if (correspondences.size() < 4 && !accelerated) return pass;
    if (lever_m == 0) lever_m = rms_lever(source, correspondences, at, pivot);
    Eigen::Isometry3d next = at;
    double cost = INFINITY;  // mean per correspondence at `at`
    if (correspondences.size() >= 4) {
      const GicpLinearisation lin =
          linearise_gicp(target, source, correspondences, at, pivot, threads, min_observed_share > 0);
      cost = lin.cost / static_cast<double>(lin.correspondences);
      const Vector6d step = observed_step(lin, min_observed_share);
      if (step.allFinite()) {
        next = perturbed(at, step, pivot);
      } else if (!accelerated) {
        return pass;
      } else {
        cost = INFINITY;  // drop the mix
      }
    }
    // A mix that fits worse than the last answer did is dropped for that answer (AA-ICP's guard).
    if (accelerated && !(cost <= last_cost)) {
      at = pass.source_to_target;
      accelerated = false;
      anderson.reset();
      continue;
    }
    last_cost = cost;
    if (cost < stall_cost * (1 - kStallShare)) {
      stall_cost = cost;
      stall_since = pass.iterations;
    }
    // Converged by PCL's rule, or caught in a cycle: a few points near the gate or midway
    // between two target points swap their nearest neighbour back and forth and the answer
    // returns to an earlier one. PCL's rule alone never ends such a cycle at the refinement's
    // tight epsilon; the answers in it agree within `convergence`.
    const Eigen::Isometry3d centred_next = centred(next);
    const bool stalled = stall_iterations > 0 && pass.iterations - stall_since >= stall_iterations;
    const bool done = stalled || small_change(centred(at), centred_next, convergence) ||
                      std::any_of(answers.begin(), answers.end(), [&](const Eigen::Isometry3d& earlier) {
                        return small_change(earlier, centred_next, convergence);
                      });
    answers.push_back(centred_next);
    pass.source_to_target = next;
    if (done) break;
    if (Eigen::AngleAxisd(start.linear().transpose() * next.linear()).angle() > max_turn_rad) return pass;
    const Vector6d mixed = anderson.next(coordinates(at, start, pivot, lever_m), coordinates(next, start, pivot, lever_m));
    at = pose_at(mixed, start, pivot, lever_m);
    accelerated = !small_change(at, next, kFloatResolutionM, kFloatResolutionM);
  }
  pass.converged = true;  // PCL: converged on a small change or at the iteration limit
  return pass;
}

PreparedRegistration register_prepared(const GicpCloud& target, const GicpCloud& source, const GicpOverlap& overlap,
                                       const Eigen::Isometry3d& guess, const GicpConfig& config,
                                       const Eigen::Vector3d* hessian_anchor, const std::atomic<bool>* cancel) {
  // As the wrapper: about the overlaps' centroids, where yaw and translation are not the same
  // motion (gicp.h, about_centroid).
  const Eigen::Vector3d pivot = config.about_centroid ? target_centroid(target, overlap) : Eigen::Vector3d::Zero();
  const Eigen::Vector3d source_pivot = config.about_centroid ? source_centroid(source, overlap) : Eigen::Vector3d::Zero();
  const int threads = std::max(config.threads, 1);
  Associator at_gate(target, source, overlap, config.max_correspondence_m);
  const double max_turn_rad = config.max_turn_deg * M_PI / 180;
  GaussNewtonPass pass =
      gauss_newton_gicp(target, source, at_gate, guess, pivot, source_pivot, config.convergence, config.max_iterations,
                        config.stall_iterations, config.min_observed_share, max_turn_rad, threads, cancel);
  if (config.refine_correspondence_m > 0) {
    Associator at_refine_gate(target, source, overlap, config.refine_correspondence_m);
    const GaussNewtonPass refined =
        gauss_newton_gicp(target, source, at_refine_gate, pass.source_to_target, pivot, source_pivot,
                          // Not on the refinement: it starts converged and creeps by design.
                          config.refine_convergence, config.max_iterations, 0, config.min_observed_share,
                          max_turn_rad, threads, cancel);
    pass = {refined.source_to_target, pass.converged && refined.converged, pass.iterations + refined.iterations};
  }
  PreparedRegistration out;
  out.registration.source_to_target = pass.source_to_target;
  // Quality at Table 1's gate whatever pass produced the answer, on every sounding as the
  // wrapper measures it (estimated from the sample).
  out.registration.quality =
      sampled_overlap_quality(target, source, overlap, pass.source_to_target, config.max_correspondence_m, threads);
  out.registration.quality.converged = pass.converged;
  if (hessian_anchor != nullptr) {
    const Eigen::Vector3d anchor = pass.source_to_target * *hessian_anchor;
    const GicpLinearisation at_answer =
        linearise_gicp(target, source, at_gate.at(pass.source_to_target, threads), pass.source_to_target, anchor,
                       threads, true);
    out.hessian.hessian = at_answer.hessian;
    out.hessian.regularisation = at_answer.regularisation;
    out.hessian.correspondences = at_answer.correspondences;
  }
  return out;
}

}  // namespace bathyslam
