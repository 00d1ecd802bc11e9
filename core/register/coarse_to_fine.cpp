#include "core/register/coarse_to_fine.h"

#include <stdexcept>

#include "core/register/gicp_solver.h"
#include "core/types/format.h"

namespace bathyslam {

double feature_density(const SubmapFeatures& a, const SubmapFeatures& b) {
  const int cells = a.valid_cells + b.valid_cells;
  return cells > 0 ? static_cast<double>(a.keypoints.size() + b.keypoints.size()) / cells : 0.0;
}

std::string to_string(RegistrationPath path) {
  return path == RegistrationPath::kDirect ? "direct" : "feature-aided";
}

RegistrationPath parse_registration_path(const std::string& text) {
  for (RegistrationPath p : {RegistrationPath::kDirect, RegistrationPath::kFeatureAided}) {
    if (text == to_string(p)) return p;
  }
  throw std::invalid_argument("registration path '" + text + "' is not known to this version of the core");
}

namespace {

// register_direct with our GICP: the same crop, as indices into the prepared submaps.
PairRegistration register_direct_prepared(const GicpCloud& target, const GicpCloud& source, const Eigen::Isometry3d& guess,
                                          const GicpConfig& gicp, double crop_margin_m, bool with_hessian,
                                          const std::atomic<bool>* cancel) {
  const GicpOverlap overlap = gicp_overlap(target, source, guess, crop_margin_m, gicp.threads);
  PairRegistration r;
  r.coarse = guess;
  r.anchor = source_centroid(source, overlap);
  r.registration.source_to_target = guess;
  const auto too_few = static_cast<std::size_t>(gicp.neighbours + 1);
  if (overlap.target_points < too_few || overlap.source_points.size() < too_few) return r;
  PreparedRegistration reg =
      register_prepared(target, source, overlap, guess, gicp, with_hessian ? &r.anchor : nullptr, cancel);
  r.registration = reg.registration;
  r.inlier_ratio = r.registration.quality.fitness;
  r.hessian = reg.hessian;
  return r;
}

}  // namespace

PairRegistration observe_at(const GicpCloud& target, const GicpCloud& source, const Eigen::Isometry3d& source_to_target,
                            const GicpConfig& gicp, double crop_margin_m) {
  const GicpOverlap overlap = gicp_overlap(target, source, source_to_target, crop_margin_m, gicp.threads);
  PairRegistration r;
  r.coarse = source_to_target;
  r.registration.source_to_target = source_to_target;
  r.anchor = source_centroid(source, overlap);
  const auto too_few = static_cast<std::size_t>(gicp.neighbours + 1);
  if (overlap.target_points < too_few || overlap.source_points.size() < too_few) return r;
  const int threads = std::max(gicp.threads, 1);
  r.registration.quality =
      sampled_overlap_quality(target, source, overlap, source_to_target, gicp.max_correspondence_m, threads);
  r.registration.quality.converged = true;
  r.inlier_ratio = r.registration.quality.fitness;
  const GicpLinearisation at = linearise_gicp(target, source, overlap, source_to_target, source_to_target * r.anchor,
                                              gicp.max_correspondence_m, threads, true);
  r.hessian.hessian = at.hessian;
  r.hessian.regularisation = at.regularisation;
  r.hessian.correspondences = at.correspondences;
  return r;
}

PairClouds prepared_pair(GicpCloudCache& cache, int target, int source, const std::atomic<bool>* cancel) {
  return {&cache.at(static_cast<std::size_t>(target)), &cache.at(static_cast<std::size_t>(source)), nullptr, nullptr, cancel};
}

OneOffPair one_off_pair(const Cloud& target, const Cloud& source, const GicpConfig& gicp) {
  if (!uses_own_gicp(gicp)) return {nullptr, nullptr, pcl_pair(target, source)};
  OneOffPair pair{prepare_gicp_cloud(target, gicp), prepare_gicp_cloud(source, gicp), {}};
  pair.clouds = {pair.target.get(), pair.source.get()};
  return pair;
}

PairRegistration register_direct(const PairClouds& clouds, const Eigen::Isometry3d& guess, const GicpConfig& gicp,
                                 double crop_margin_m, bool with_hessian) {
  if (clouds.prepared_target != nullptr) {
    return register_direct_prepared(*clouds.prepared_target, *clouds.prepared_source, guess, gicp, crop_margin_m,
                                    with_hessian, clouds.cancel);
  }
  const Cloud& target = *clouds.target;
  const Cloud& source = *clouds.source;
  const Cloud::Ptr target_overlap = crop_to_overlap(target, source, guess.inverse(), crop_margin_m);
  const Cloud::Ptr source_overlap = crop_to_overlap(source, target, guess, crop_margin_m);
  PairRegistration r;
  r.coarse = guess;
  r.anchor = centroid(*source_overlap);
  r.registration.source_to_target = guess;
  // GICP needs each point's neighbours for its covariances; a sliver of overlap has too few.
  const auto too_few = static_cast<std::size_t>(gicp.neighbours + 1);
  if (target_overlap->size() < too_few || source_overlap->size() < too_few) return r;  // not converged, no overlap
  r.registration = register_gicp(target_overlap, source_overlap, guess, gicp);
  r.inlier_ratio = r.registration.quality.fitness;
  if (with_hessian) r.hessian = gicp_hessian(*target_overlap, *source_overlap, r.registration.source_to_target, r.anchor, gicp);
  return r;
}

CoarseStart coarse_start(const SubmapFeatures& target_features, const SubmapFeatures& source_features,
                         const Eigen::Isometry3d& guess, const CoarseToFineConfig& config, uint64_t seed) {
  CoarseStart c;
  c.feature_density = feature_density(target_features, source_features);
  c.start = guess;
  c.gicp = config.gicp;
  if (c.feature_density < config.switching.min_feature_density) {
    c.why = format("feature density %.4f < %.4f", c.feature_density, config.switching.min_feature_density);
    return c;
  }
  const std::vector<FeatureMatch> matches =
      match_features(source_features.keypoints, target_features.keypoints, guess, config.matching);
  c.matches = static_cast<int>(matches.size());
  if (c.matches < config.matching.min_matches) {
    c.why = format("too few matches %.0f < %.0f", static_cast<double>(matches.size()),
                   static_cast<double>(config.matching.min_matches));
    return c;
  }
  std::vector<Eigen::Vector3d> from, to;
  for (const FeatureMatch& m : matches) {
    from.push_back(source_features.keypoints[m.source].position);
    to.push_back(target_features.keypoints[m.target].position);
  }
  RansacConfig ransac = config.ransac;
  ransac.seed = seed;
  const RansacResult coarse = adaptive_ransac(from, to, ransac);

  // GICP refines the feature estimate on the overlap that estimate predicts.
  c.path = RegistrationPath::kFeatureAided;
  c.why = format("feature density %.4f >= %.4f", c.feature_density, config.switching.min_feature_density) + ", " +
          std::to_string(matches.size()) + " matches";
  c.start = coarse.source_to_target;
  if (config.feature_refine_correspondence_m > 0) {
    c.gicp.about_centroid = 1;
    c.gicp.refine_correspondence_m = config.feature_refine_correspondence_m;
  }
  c.ransac_inliers = static_cast<int>(coarse.inliers.size());
  c.ransac_inlier_ratio = coarse.inlier_ratio;
  c.competitor_inliers = coarse.competitor_inliers;
  c.competitor_separation_m = coarse.competitor_separation_m;
  return c;
}

namespace {

// `r` with the switch's decision and, on the feature-aided path, RANSAC's figures.
PairRegistration with_switch_decision(PairRegistration r, const CoarseStart& c) {
  r.path = c.path;
  r.why = c.why;
  r.feature_density = c.feature_density;
  r.matches = c.matches;
  if (c.path == RegistrationPath::kFeatureAided) {
    r.ransac_inliers = c.ransac_inliers;
    r.competitor_inliers = c.competitor_inliers;
    r.competitor_separation_m = c.competitor_separation_m;
    r.inlier_ratio = c.ransac_inlier_ratio;
  }
  return r;
}

}  // namespace

PairRegistration register_from_start(const CoarseStart& c, const PairClouds& clouds,
                                     const SubmapFeatures& target_features, const SubmapFeatures& source_features,
                                     const CoarseToFineConfig& config, bool with_hessian) {
  const auto from = [&](const Eigen::Isometry3d& start) {
    PairRegistration r = with_switch_decision(register_direct(clouds, start, c.gicp, config.crop_margin_m, with_hessian), c);
    r.uniqueness = probe_uniqueness(target_features.grid, source_features.grid, r.registration.source_to_target, config.uniqueness);
    return r;
  };
  PairRegistration r = from(c.start);
  if (c.path != RegistrationPath::kDirect) return r;
  const auto fits_better_elsewhere = [&](const Uniqueness& u) {
    return u.probed && u.distinctness() < config.restart_below_distinctness &&
           u.cost_at_answer_m2 <= config.restart_max_answer_share * u.typical_cost_m2;
  };
  for (int k = 0; k < config.best_basin_restarts && fits_better_elsewhere(r.uniqueness); ++k) {
    Eigen::Isometry3d start = r.registration.source_to_target;
    start.pretranslate(Eigen::Vector3d(r.uniqueness.alternative_offset_m.x(), r.uniqueness.alternative_offset_m.y(), 0));
    PairRegistration again = from(start);
    if (!again.registration.quality.converged || !again.uniqueness.probed ||
        !(again.uniqueness.cost_at_answer_m2 < r.uniqueness.cost_at_answer_m2)) {
      break;
    }
    r = std::move(again);
  }
  return r;
}

PairRegistration unregistered(const CoarseStart& c, const Eigen::Isometry3d& guess) {
  PairRegistration r;
  r.coarse = guess;
  r.registration.source_to_target = guess;
  return with_switch_decision(r, c);
}

PairRegistration register_coarse_to_fine(const PairClouds& clouds, const SubmapFeatures& target_features,
                                         const SubmapFeatures& source_features, const Eigen::Isometry3d& guess,
                                         const CoarseToFineConfig& config, uint64_t seed, bool with_hessian) {
  return register_from_start(coarse_start(target_features, source_features, guess, config, seed), clouds,
                             target_features, source_features, config, with_hessian);
}

}  // namespace bathyslam
