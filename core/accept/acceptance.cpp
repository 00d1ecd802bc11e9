#include "core/accept/acceptance.h"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <utility>

#include "core/types/format.h"

namespace bathyslam {
namespace {

// Linear between knots (x ascending), constant beyond the ends.
template <std::size_t N>
double piecewise(const std::array<std::pair<double, double>, N>& knots, double x) {
  if (x <= knots.front().first) return knots.front().second;
  for (std::size_t k = 1; k < N; ++k) {
    if (x <= knots[k].first) {
      const auto [x0, y0] = knots[k - 1];
      const auto [x1, y1] = knots[k];
      return y0 + (y1 - y0) * (x - x0) / (x1 - x0);
    }
  }
  return knots.back().second;
}

}  // namespace

Rejection rejection_of(const PairRegistration& r, const Eigen::Isometry3d& guess, const AcceptanceConfig& config,
                       bool loop_closure) {
  using enum RejectionKind;
  const RegistrationQuality& q = r.registration.quality;
  if (loop_closure && r.path == RegistrationPath::kDirect) return {kLoopWithoutFeatures, r.why};
  if (q.overlap_points == 0) return {kNoOverlap, "no source sounding within the gate of a target sounding"};
  if (!q.converged) return {kNotConverged, "GICP stopped unconverged"};
  if (r.inlier_ratio < config.min_inlier_ratio) return {kInlierRatio, format("%.2f < %.2f", r.inlier_ratio, config.min_inlier_ratio)};
  if (q.overlap_mse_m2 > config.max_overlap_mse_m2) {
    return {kOverlapMse, format("%.2f m2 > %.2f m2", q.overlap_mse_m2, config.max_overlap_mse_m2)};
  }
  if (static_cast<int>(q.overlap_points) < config.min_overlap_points) {
    return {kOverlapPoints, format("%.0f < %.0f", static_cast<double>(q.overlap_points), config.min_overlap_points)};
  }
  if (config.max_competitor_ratio > 0 && r.path == RegistrationPath::kFeatureAided && r.ransac_inliers > 0) {
    const double ratio = static_cast<double>(r.competitor_inliers) / r.ransac_inliers;
    if (ratio >= config.max_competitor_ratio) {
      return {kCompetitor, format("a second alignment %.1f m away has %.0f of the winner's %.0f inliers", r.competitor_separation_m,
                                  static_cast<double>(r.competitor_inliers), static_cast<double>(r.ransac_inliers))};
    }
  }
  if (config.min_distinctness > 0 && r.path == RegistrationPath::kFeatureAided) {
    const Uniqueness& u = r.uniqueness;
    if (!u.probed) return {kNotUnique, "too little terrain overlap to probe its uniqueness"};
    if (u.distinctness() < config.min_distinctness) {
      return {kNotUnique, format("the terrain also fits %.1f m away: distinctness %.1f < %.1f", u.alternative_offset_m.norm(),
                                 u.distinctness(), config.min_distinctness)};
    }
  }
  const double moved = (r.registration.source_to_target.translation() - guess.translation()).norm();
  if (moved > config.max_translation_m) return {kTranslation, format("%.1f m > %.1f m", moved, config.max_translation_m)};
  return {};
}

double inlier_ratio_weight(double inlier_ratio) {
  return piecewise<3>({{{0.25, 0.2}, {0.5, 0.6}, {0.8, 1.0}}}, inlier_ratio);
}

double overlap_mse_weight(double mse_m2) {
  return piecewise<4>({{{0.05, 1.0}, {0.2, 0.7}, {1.0, 0.3}, {5.0, 0.05}}}, mse_m2);
}

double overlap_points_weight(double points) {
  return piecewise<3>({{{500, 0.2}, {2000, 0.6}, {10000, 1.0}}}, points);
}

double quality_weight(const PairRegistration& r) {
  const RegistrationQuality& q = r.registration.quality;
  return inlier_ratio_weight(r.inlier_ratio) * overlap_mse_weight(q.overlap_mse_m2) *
         overlap_points_weight(static_cast<double>(q.overlap_points));
}

Information6 quality_information(const PairRegistration& r, const QualityConfig& config,
                                 const Eigen::Matrix3d& level_from_target) {
  const double weight = quality_weight(r);
  if (config.information_from_hessian) {
    if (r.hessian.correspondences == 0) {
      throw std::invalid_argument("quality.information_from_hessian needs the registration's Hessian");
    }
    Eigen::Matrix<double, 6, 1> best_sigmas;
    best_sigmas << config.best_sigma_translation_m, config.best_sigma_rotation_rad;
    Information6 information = observed_information(rotated(r.hessian, level_from_target), weight, best_sigmas,
                                                    config.hessian_full_share, config.hessian_zero_share);
    // The direct path's horizontal may yet be taken away (aliases, doubt, reach), and then its
    // depth was measured where its guess put it.
    if (r.path == RegistrationPath::kDirect && config.direct_depth_from_relief) {
      information = with_depth_capped_by_relief(information, r.uniqueness);
    }
    return information;
  }
  Information6 information = weight * information_from_sigmas(config.best_sigma_translation_m, config.best_sigma_rotation_rad);
  if (r.path == RegistrationPath::kDirect) {
    for (int k : {0, 1, 5}) information(k, k) *= config.direct_horizontal_share;
    if (config.direct_depth_from_relief) information = with_depth_capped_by_relief(information, r.uniqueness);
  }
  return information;
}

Information6 with_depth_capped_by_relief(Information6 information, const Uniqueness& uniqueness) {
  const double variance = uniqueness.local_cost_m2;
  if (!uniqueness.probed || variance <= 0 || information(2, 2) <= 1.0 / variance) return information;
  const double scale = std::sqrt(1.0 / (variance * information(2, 2)));
  information.row(2) *= scale;
  information.col(2) *= scale;
  return information;
}

}  // namespace bathyslam
