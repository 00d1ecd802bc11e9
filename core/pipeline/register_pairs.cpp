#include "core/pipeline/register_pairs.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include "core/parallel/parallel_for.h"
#include "core/pipeline/robust_backend.h"
#include "core/types/format.h"

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

// Empty when the plan registers a featureless loop closure directly and dead reckoning keeps the
// truth where a wrong answer would be found out; otherwise why not, for the report (such a loop
// keeps depth, roll and pitch only). With the alias rule that is the uniqueness probe's search
// radius: had GICP stopped anywhere but the truth, the truth would be among the probe's
// competitors there, and the answer would lose its position along them (resolve_alias). Without
// it, GICP's own gate. Both use DR's covariance between the two submaps, not the batch's
// corrected guess's, so they err long (direct_loops.reach_sigmas, off by default); and the
// radii follow the sounding footprint while Table 1's DR sigmas, before the survey's own are
// estimated, do not.
std::string direct_loop_reach(const CandidatePair& pair, const DrNoiseModel& dr, const PipelineConfig& config,
                              const Plan& plan) {
  if (!plan.direct_loops) return "direct loop closures off";
  if (config.direct_loops.reach_sigmas <= 0) return "";
  const double sigma = dr_horizontal_sigma(dr, pair.target, pair.source);
  const double reach = plan.alias_from_prior ? config.registration.uniqueness.search_radius_m
                                             : config.registration.gicp.max_correspondence_m;
  if (config.direct_loops.reach_sigmas * sigma <= reach) return "";
  return format("guess beyond reach: %.1f x DR sigma %.2f m > %.1f m", config.direct_loops.reach_sigmas, sigma, reach);
}

// Squared Mahalanobis distance between two answers of one pair, at the anchor and in yaw, under
// the x, y and yaw block of `information`.
double answers_apart2(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const Eigen::Vector3d& anchor,
                      const Information6& information) {
  const Eigen::Vector3d moved = a * anchor - b * anchor;
  const Eigen::Matrix3d turn = a.linear() * b.linear().transpose();
  const Eigen::Vector3d d(moved.x(), moved.y(), std::atan2(turn(1, 0), turn(0, 0)));
  return d.dot(xy_yaw_block(information) * d);
}

// Why a registration's horizontal answer is not the overlap's, or nullopt when nothing says so:
// the terrain fits much better a few metres away (quality.max_nearby_improvement), or, on the
// direct path, GICP does not come back to the answer from two starts either side of the guess
// across both horizontal axes (quality.start_check_share). `others` gets where else the answer
// was found, in the level frame `level_from_target` gives.
std::optional<std::string> horizontal_doubt(const PairRegistration& reg, const Information6& information,
                                            const std::function<PairRegistration(const Eigen::Isometry3d&)>& from,
                                            const PipelineConfig& config, const Eigen::Matrix3d& level_from_target,
                                            OtherAnswers& others) {
  const QualityConfig& quality = config.quality;
  const double improvement = reg.uniqueness.nearby_improvement();
  if (quality.max_nearby_improvement > 0 && improvement > quality.max_nearby_improvement) {
    others.landings.push_back(level_offset(level_from_target, reg.uniqueness.nearby_offset_m));
    return format("the terrain fits %.1fx better %.1f m away", improvement, reg.uniqueness.nearby_offset_m.norm());
  }
  const double spread = quality.start_check_share * config.registration.gicp.max_correspondence_m;
  if (reg.path != RegistrationPath::kDirect || spread <= 0) return std::nullopt;
  const double chi2 = config.robustness.pcm.plausibility.chi2_threshold;
  std::optional<std::string> doubt;
  for (const Eigen::Vector2d& side : {Eigen::Vector2d(1, 1), Eigen::Vector2d(-1, 1)}) {
    const Eigen::Vector2d shift = spread * side.normalized();
    Eigen::Isometry3d start = reg.coarse;
    start.pretranslate(Eigen::Vector3d(shift.x(), shift.y(), 0));
    const PairRegistration again = from(start);
    const double m2 = answers_apart2(again.registration.source_to_target, reg.registration.source_to_target, reg.anchor,
                                     information);
    const Eigen::Vector3d landed =
        again.registration.source_to_target * reg.anchor - reg.registration.source_to_target * reg.anchor;
    others.shifts.push_back(level_offset(level_from_target, shift));
    others.landings.push_back(level_offset(level_from_target, landed.head<2>()));
    if (!again.registration.quality.converged) {
      others.lost = true;
      doubt = format("from %.1f m aside GICP does not converge", spread);
    } else if (m2 > chi2) {
      if (!doubt) doubt = format("from %.1f m aside GICP lands %.2f m away (Mahalanobis2 %.1f > %.1f)", spread,
                                 landed.norm(), m2, chi2);
    }
    if (doubt && !quality.doubt_widens) break;  // only widening needs both landings
  }
  return doubt;
}

Constraint register_pair(const Candidate& candidate, const std::vector<Eigen::Isometry3d>& estimate,
                         const RegistrationInputs& in, const PipelineConfig& config, const Plan& plan,
                         const std::atomic<bool>* cancel) {
  const CandidatePair& pair = candidate.pair;
  const Eigen::Isometry3d guess = estimate[pair.target].inverse() * estimate[pair.source];
  const bool with_hessian = plan.hessian_information;
  // Asked for only when GICP runs: ours prepares a submap on its first registration, and the
  // switch may leave a loop closure unregistered.
  auto clouds = [&] {
    return plan.own_gicp ? prepared_pair(in.prepared, pair.target, pair.source, cancel)
                         : pcl_pair(*in.clouds[pair.target], *in.clouds[pair.source]);
  };
  PairRegistration reg;
  bool direct_loop = false;  // a loop closure the switch sends down the direct path
  std::string loop_reach;    // why such a loop is out of the direct path's reach; empty: within it
  if (plan.features) {
    // RANSAC reproducible per pair, whatever thread or batch registers it.
    const uint64_t seed = config.registration.ransac.seed ^
                          (static_cast<uint64_t>(pair.target) << 32 | static_cast<uint64_t>(pair.source));
    const SubmapFeatures& target_features = in.features[pair.target];
    const SubmapFeatures& source_features = in.features[pair.source];
    const CoarseStart coarse = coarse_start(target_features, source_features, guess, config.registration, seed);
    // A loop the switch sends down the direct path: without direct loops acceptance refuses it
    // whatever GICP would answer, so GICP is not run. With them, beyond GICP's reach of its
    // guess (direct_loop_reach) it is registered for its depth, roll and pitch only.
    direct_loop = candidate.type == ConstraintType::kLoop && coarse.path == RegistrationPath::kDirect;
    if (plan.quality_aware && direct_loop) loop_reach = direct_loop_reach(pair, in.dr, config, plan);
    if (plan.quality_aware && direct_loop && !plan.direct_loops) {
      reg = unregistered(coarse, guess);
      reg.why += ", " + loop_reach;
    } else {
      reg = register_from_start(coarse, clouds(), target_features, source_features, config.registration, with_hessian);
    }
  } else {
    reg = register_direct(clouds(), guess, config.registration.gicp, config.registration.crop_margin_m, with_hessian);
  }
  Constraint c = constraint_of(candidate, reg, guess);
  if (plan.quality_aware) {
    // With the prior's word on aliases, resolve_alias applies the uniqueness test instead.
    AcceptanceConfig acceptance = config.acceptance;
    if (plan.alias_from_prior) acceptance.min_distinctness = 0;
    c.rejection = rejection_of(reg, guess, acceptance, candidate.type == ConstraintType::kLoop && !plan.direct_loops);
    if (c.accepted()) {
      const Eigen::Matrix3d level_from_target =
          level_from_body(Eigen::Quaterniond(estimate[pair.target].rotation())).toRotationMatrix();
      c.information = quality_information(reg, config.quality, level_from_target);
      if (reg.path == RegistrationPath::kDirect && !config.quality.direct_yaw) {
        c.information.row(5).setZero(), c.information.col(5).setZero();
      }
      const auto from = [&](const Eigen::Isometry3d& start) {
        return register_direct(clouds(), start, config.registration.gicp, config.registration.crop_margin_m, false);
      };
      std::optional<std::string> doubt;
      OtherAnswers others;
      if (!loop_reach.empty()) {
        doubt = loop_reach;
      } else if (carries_horizontal_information(c.information)) {
        doubt = horizontal_doubt(reg, c.information, from, config, level_from_target, others);
      }
      if (doubt) {
        c.horizontal_doubt = *doubt;
        c.information = config.quality.doubt_widens ? widened_by_doubt(c.information, others, c.horizontal_spread)
                                                    : without_horizontal(c.information);
      }
    }
  } else {
    c.rejection = unless_converged(reg);
    c.information = information_from_sigmas(config.uniform_information.sigma_translation_m,
                                             config.uniform_information.sigma_rotation_rad);
  }
  c.registered_information = c.information;
  judge_with_prior(c, in.dr, in.alias_dr, in.dr_poses, config, plan);
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
  if (plan.own_gicp) {
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
