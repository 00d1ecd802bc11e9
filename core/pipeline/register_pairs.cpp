#include "core/pipeline/register_pairs.h"

#include <algorithm>

#include "core/parallel/parallel_for.h"
#include "core/pipeline/robust_backend.h"

namespace bathyslam {
namespace {

// A registration's constraint, with DR roll and pitch kept (keep_dr_roll_pitch) and the
// switch's record; acceptance and information are the plan's to set.
Constraint constraint_of(const Candidate& candidate, const PairRegistration& reg, const Eigen::Isometry3d& guess) {
  Constraint c;
  c.type = candidate.type;
  c.from = candidate.pair.target;
  c.to = candidate.pair.source;
  c.measured = keep_dr_roll_pitch(reg.registration.source_to_target, guess, reg.anchor);
  c.anchor = reg.anchor;
  c.guess = guess;
  c.quality = reg.registration.quality;
  c.overlap_fraction = candidate.pair.overlap_fraction;
  c.path = reg.path;
  c.path_reason = reg.why;
  c.feature_density = reg.feature_density;
  c.matches = reg.matches;
  c.inlier_ratio = reg.inlier_ratio;
  c.competitor_inliers = reg.competitor_inliers;
  c.competitor_separation_m = reg.competitor_separation_m;
  c.uniqueness = reg.uniqueness;
  return c;
}

// The paper's baseline keeps every registration that converged on some overlap.
Rejection unless_converged(const PairRegistration& reg) {
  if (reg.registration.quality.overlap_points == 0) return {RejectionKind::kNoOverlap, ""};
  if (!reg.registration.quality.converged) return {RejectionKind::kNotConverged, ""};
  return {};
}

Constraint register_pair(const Candidate& candidate, const std::vector<Eigen::Isometry3d>& estimate,
                         const RegistrationInputs& in, const PipelineConfig& config, const Plan& plan,
                         const std::atomic<bool>* cancel) {
  const CandidatePair& pair = candidate.pair;
  const Eigen::Isometry3d guess = estimate[pair.target].inverse() * estimate[pair.source];
  const bool with_hessian = plan.quality_aware && config.quality.information_from_hessian;
  // Ours registers on the prepared submaps alone (coarse_to_fine.h): no clouds are held for it.
  static const Cloud kNone;
  const Cloud& target = in.clouds.empty() ? kNone : *in.clouds[pair.target];
  const Cloud& source = in.clouds.empty() ? kNone : *in.clouds[pair.source];
  auto prepared = [&] { return prepared_pair(in.prepared, config.registration.gicp, pair.target, pair.source, cancel); };
  PairRegistration reg;
  if (plan.features) {
    // RANSAC reproducible per pair, whatever thread or batch registers it.
    const uint64_t seed = config.registration.ransac.seed ^
                          (static_cast<uint64_t>(pair.target) << 32 | static_cast<uint64_t>(pair.source));
    const SubmapFeatures& target_features = in.features[pair.target];
    const SubmapFeatures& source_features = in.features[pair.source];
    const CoarseStart coarse = coarse_start(target_features, source_features, guess, config.registration, seed);
    // Acceptance lets only the feature-aided path close a loop (rejection_of): a loop the switch
    // sends down the direct path is refused whatever GICP would answer, so GICP is not run (a
    // third of `lake`'s registrations).
    if (plan.quality_aware && candidate.type == ConstraintType::kLoop && coarse.path == RegistrationPath::kDirect) {
      reg = unregistered(coarse, guess);
    } else {
      reg = register_from_start(coarse, target, source, target_features, source_features, config.registration,
                                with_hessian, prepared());
    }
  } else {
    reg = register_direct(target, source, guess, config.registration.gicp, config.registration.crop_margin_m, with_hessian,
                          prepared());
  }
  Constraint c = constraint_of(candidate, reg, guess);
  if (plan.quality_aware) {
    c.rejection = rejection_of(reg, guess, config.acceptance, candidate.type == ConstraintType::kLoop);
    const Eigen::Matrix3d level_from_target =
        level_from_body(Eigen::Quaterniond(estimate[pair.target].rotation())).toRotationMatrix();
    if (c.accepted()) c.information = quality_information(reg, config.quality, level_from_target);
  } else {
    c.rejection = unless_converged(reg);
    c.information = information_from_sigmas(config.uniform_information.sigma_translation_m,
                                             config.uniform_information.sigma_rotation_rad);
  }
  if (plan.dr_gate) gate_against_dead_reckoning(c, in.dr, in.dr_poses, config.robustness.pcm.plausibility);
  return c;
}

}  // namespace

std::vector<Constraint> register_pairs(const std::vector<Candidate>& candidates,
                                       const std::vector<Eigen::Isometry3d>& estimate, const RegistrationInputs& inputs,
                                       const PipelineConfig& config, const Plan& plan, const std::atomic<bool>* cancel) {
  // Our GICP prepares each submap on its first registration, and a pair whose submap another
  // thread is preparing waits for it: consecutive candidates share a submap, so with the pairs
  // alone the two threads took turns. The adjacent pairs' submaps are prepared first, in the
  // same loop (no barrier between); a loop closure's older submap only when its pair
  // registers, because the switch may send that pair down the direct path, unregistered.
  std::vector<int> to_prepare;
  if (config.registration.gicp.engine == 1) {
    for (const Candidate& c : candidates) {
      if (c.type == ConstraintType::kAdjacent) to_prepare.insert(to_prepare.end(), {c.pair.target, c.pair.source});
    }
    std::sort(to_prepare.begin(), to_prepare.end());
    to_prepare.erase(std::unique(to_prepare.begin(), to_prepare.end()), to_prepare.end());
  }
  std::vector<Constraint> constraints(candidates.size());
  parallel_for(to_prepare.size() + candidates.size(), plan.threads, cancel, [&](std::size_t k) {
    if (k < to_prepare.size()) {
      inputs.prepared.at(static_cast<std::size_t>(to_prepare[k]));
      return;
    }
    k -= to_prepare.size();
    constraints[k] = register_pair(candidates[k], estimate, inputs, config, plan, cancel);
  });
  return constraints;
}

}  // namespace bathyslam
