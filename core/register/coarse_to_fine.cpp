#include "core/register/coarse_to_fine.h"

#include <stdexcept>

#include "core/types/format.h"

namespace bathyslam {

SubmapFeatures extract_features(const Submap& submap, const GridConfig& grid, const KeypointConfig& keypoints) {
  const TerrainGrid terrain = grid_terrain(submap.points, grid);
  return {detect_keypoints(terrain, keypoints), terrain.valid_cells(), terrain};
}

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

PairRegistration register_direct(const Cloud& target, const Cloud& source, const Eigen::Isometry3d& guess,
                                 const GicpConfig& gicp, double crop_margin_m, bool with_hessian) {
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

PairRegistration register_coarse_to_fine(const Cloud& target, const Cloud& source, const SubmapFeatures& target_features,
                                         const SubmapFeatures& source_features, const Eigen::Isometry3d& guess,
                                         const CoarseToFineConfig& config, uint64_t seed, bool with_hessian) {
  const double density = feature_density(target_features, source_features);
  auto direct = [&](std::string why) {
    PairRegistration r = register_direct(target, source, guess, config.gicp, config.crop_margin_m, with_hessian);
    r.path = RegistrationPath::kDirect;
    r.why = std::move(why);
    r.feature_density = density;
    r.uniqueness = probe_uniqueness(target_features.grid, source_features.grid, r.registration.source_to_target, config.uniqueness);
    return r;
  };
  if (density < config.switching.min_feature_density) {
    return direct(format("feature density %.4f < %.4f", density, config.switching.min_feature_density));
  }
  const std::vector<FeatureMatch> matches =
      match_features(source_features.keypoints, target_features.keypoints, guess, config.matching);
  if (static_cast<int>(matches.size()) < config.matching.min_matches) {
    PairRegistration r = direct(format("too few matches %.0f < %.0f", static_cast<double>(matches.size()),
                                       static_cast<double>(config.matching.min_matches)));
    r.matches = static_cast<int>(matches.size());
    return r;
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
  GicpConfig refine = config.gicp;
  if (config.feature_refine_correspondence_m > 0) {
    refine.about_centroid = 1;
    refine.refine_correspondence_m = config.feature_refine_correspondence_m;
  }
  PairRegistration r =
      register_direct(target, source, coarse.source_to_target, refine, config.crop_margin_m, with_hessian);
  r.path = RegistrationPath::kFeatureAided;
  r.why = format("feature density %.4f >= %.4f", density, config.switching.min_feature_density) + ", " +
          std::to_string(matches.size()) + " matches";
  r.feature_density = density;
  r.matches = static_cast<int>(matches.size());
  r.ransac_inliers = static_cast<int>(coarse.inliers.size());
  r.competitor_inliers = coarse.competitor_inliers;
  r.competitor_separation_m = coarse.competitor_separation_m;
  r.uniqueness = probe_uniqueness(target_features.grid, source_features.grid, r.registration.source_to_target, config.uniqueness);
  r.inlier_ratio = coarse.inlier_ratio;
  return r;
}

}  // namespace bathyslam
