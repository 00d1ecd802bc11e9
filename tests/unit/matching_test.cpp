#include <gtest/gtest.h>

#include <random>

#include "core/accept/acceptance.h"
#include "core/matching/adaptive_ransac.h"
#include "core/register/coarse_to_fine.h"
#include "tests/unit/synthetic_terrain.h"

namespace bathyslam {
namespace {

double angle_deg(const Eigen::Isometry3d& t) { return Eigen::AngleAxisd(t.rotation()).angle() * 180 / M_PI; }

TEST(AdaptiveRansac, RecoversAKnownTransformFromMatchesThatAre60PercentOutliers) {
  const Eigen::Isometry3d truth = planar_pose(3.2, -7.5, 12.0);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> where(-25, 25), depth(8, 12);
  std::normal_distribution<double> noise(0, 0.05);
  std::vector<Eigen::Vector3d> source, target;
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3d s(where(rng), where(rng), depth(rng));
    source.push_back(s);
    // Every 5 matches: 2 inliers, 3 outliers, so good and bad are mixed through the order.
    if (i % 5 < 2) {
      target.push_back(truth * s + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    } else {
      target.emplace_back(where(rng), where(rng), depth(rng));
    }
  }
  const RansacResult r = adaptive_ransac(source, target);
  const Eigen::Isometry3d error = truth.inverse() * r.source_to_target;
  EXPECT_LT(error.translation().norm(), 0.1);
  EXPECT_LT(angle_deg(error), 0.5);
  EXPECT_NEAR(r.inlier_ratio, 0.4, 0.03);
  EXPECT_LT(r.threshold_m, 1.0) << "the threshold adapted to the inliers' noise";
  const RansacResult again = adaptive_ransac(source, target);
  EXPECT_TRUE(again.source_to_target.isApprox(r.source_to_target)) << "deterministic for a seed";
}

struct TerrainPair {
  Cloud::Ptr target, source;
  SubmapFeatures target_features, source_features;
};

// Two submaps of `terrain`: the target frame at the world origin, the source at `source_pose`.
TerrainPair pair_of(const SyntheticTerrain& target_terrain, const SyntheticTerrain& source_terrain,
                   const Eigen::Isometry3d& source_pose) {
  Submap a, b;
  a.points = target_terrain.sample(Eigen::Isometry3d::Identity(), 0.03, 5);
  b.points = source_terrain.sample(source_pose, 0.03, 6);
  return {voxel_filter(a.points), voxel_filter(b.points), extract_features(a, {}, {}), extract_features(b, {}, {})};
}

// Sand waves 8 m apart: half the matches agree with the truth, the other half with the truth
// shifted by one wavelength. The competitor is that second solution, with about half the
// support; with random outliers instead, no distinct solution has more than chance support.
TEST(AdaptiveRansac, ReportsAnAliasedSecondSolutionAndNoneWhereThereIsNone) {
  const Eigen::Isometry3d truth = planar_pose(3.2, -7.5, 12.0);
  const Eigen::Isometry3d alias = planar_pose(8.0, 0.0, 0.0) * truth;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> where(-25, 25), depth(8, 12);
  std::normal_distribution<double> noise(0, 0.05);
  auto matches = [&](bool aliased) {
    std::vector<Eigen::Vector3d> source, target;
    for (int i = 0; i < 80; ++i) {
      const Eigen::Vector3d s(where(rng), where(rng), depth(rng));
      const Eigen::Vector3d n(noise(rng), noise(rng), noise(rng));
      source.push_back(s);
      if (i % 2 == 0) target.push_back(truth * s + n);
      else if (aliased) target.push_back(alias * s + n);
      else target.emplace_back(where(rng), where(rng), depth(rng));
    }
    return std::pair{source, target};
  };
  const auto [source, target] = matches(true);
  const RansacResult aliased = adaptive_ransac(source, target);
  EXPECT_GE(aliased.inliers.size(), 38u);
  EXPECT_GE(aliased.competitor_inliers, 34);
  EXPECT_NEAR(aliased.competitor_separation_m, 8.0, 0.5);

  const auto [clean_source, clean_target] = matches(false);
  const RansacResult clean = adaptive_ransac(clean_source, clean_target);
  EXPECT_LT((truth.inverse() * clean.source_to_target).translation().norm(), 0.1);
  EXPECT_LT(clean.competitor_inliers, 8);
}

TEST(Acceptance, APairWithACompetingAlignmentOfHalfTheSupportIsAmbiguous) {
  PairRegistration r;
  r.path = RegistrationPath::kFeatureAided;
  r.registration.quality = {true, 0.8, 5000, 0.02};
  r.inlier_ratio = 0.6;
  r.ransac_inliers = 40;
  r.competitor_inliers = 10;
  r.competitor_separation_m = 8.0;
  r.uniqueness.probed = true;  // and the terrain fits only at the answer
  r.uniqueness.cost_at_answer_m2 = 0.001;
  r.uniqueness.alternative_cost_m2 = 0.2;
  const Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
  EXPECT_EQ(rejection_of(r, guess, {}, true).kind, RejectionKind::kNone);
  r.competitor_inliers = 20;
  EXPECT_EQ(rejection_of(r, guess, {}, true).kind, RejectionKind::kCompetitor);
  AcceptanceConfig off;
  off.max_competitor_ratio = 0;
  r.uniqueness.alternative_cost_m2 = 0.005;  // ambiguous terrain too, with its test off as well
  off.min_distinctness = 0;
  EXPECT_EQ(rejection_of(r, guess, off, true).kind, RejectionKind::kNone) << "0 turns the test off (the paper's method)";
  r.competitor_inliers = 10;
  EXPECT_EQ(rejection_of(r, guess, {}, true).kind, RejectionKind::kNotUnique);
}

TEST(ObservabilitySwitch, FlatSubmapsGoDirectAndRoughOnesFeatureAided) {
  const Eigen::Isometry3d truth = planar_pose(6.0, 4.0, 8.0);
  const Eigen::Isometry3d guess = planar_pose(7.5, 2.8, 10.0) * Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0));
  const CoarseToFineConfig config;

  const SyntheticTerrain flat = SyntheticTerrain::flat();
  const TerrainPair f = pair_of(flat, flat, truth);
  const PairRegistration direct = register_coarse_to_fine(one_off_pair(*f.target, *f.source, config.gicp).clouds, f.target_features, f.source_features,
                                                          guess, config, 1);
  EXPECT_EQ(direct.path, RegistrationPath::kDirect) << direct.why;
  EXPECT_LT(direct.feature_density, config.switching.min_feature_density);

  const SyntheticTerrain rough = SyntheticTerrain::with_mounds(21);
  const TerrainPair r = pair_of(rough, rough, truth);
  const PairRegistration aided = register_coarse_to_fine(one_off_pair(*r.target, *r.source, config.gicp).clouds, r.target_features, r.source_features,
                                                         guess, config, 1);
  ASSERT_EQ(aided.path, RegistrationPath::kFeatureAided) << aided.why;
  EXPECT_GE(aided.matches, config.matching.min_matches);
  const Eigen::Isometry3d error = truth.inverse() * aided.registration.source_to_target;
  EXPECT_LT(error.translation().norm(), 0.1);
  EXPECT_LT(angle_deg(error), 0.3);
  EXPECT_EQ(rejection_of(aided, guess, {}, true).kind, RejectionKind::kNone) << "a good loop closure is accepted";
}

TEST(LoopClosure, TwoDifferentPlacesOfSimilarRoughnessAreRejected) {
  // Same kind of ground, different mounds: dead reckoning claims they overlap.
  const SyntheticTerrain here = SyntheticTerrain::with_mounds(31), there = SyntheticTerrain::with_mounds(32);
  const Eigen::Isometry3d claimed = planar_pose(6.0, 4.0, 8.0);
  const TerrainPair p = pair_of(here, there, claimed);
  const CoarseToFineConfig config;
  const PairRegistration r = register_coarse_to_fine(one_off_pair(*p.target, *p.source, config.gicp).clouds, p.target_features, p.source_features,
                                                     claimed, config, 1);
  EXPECT_TRUE(rejection_of(r, claimed, {}, true).rejected()) << "accepted: " << r.why << ", inliers " << r.inlier_ratio;
}

// Sand waves 6 m apart, 1.2 m crest to trough, with a few low mounds on them, and dead reckoning
// 4 m off across the crests: GICP from the guess settles in the neighbouring trough, 6 m from
// the truth. The probe about that answer finds the true basin fitting better (the mounds fit only
// there), and GICP started again there lands on the truth.
TEST(DirectRegistration, StartsAgainInTheBasinThatFitsBetterOnAPeriodicSeabed) {
  SyntheticTerrain mounds = SyntheticTerrain::with_mounds(51, 5);
  for (double& h : mounds.heights) h *= 0.25;  // 0.2-0.4 m: the waves are the relief, the mounds tell troughs apart
  const auto sample = [&](const Eigen::Isometry3d& frame, uint64_t seed) {
    std::vector<Eigen::Vector3f> points = mounds.sample(frame, 0.02, seed);
    for (Eigen::Vector3f& p : points) {
      const Eigen::Vector3d world = frame * p.cast<double>();
      const double waves = 0.6 * std::sin(2 * M_PI * world.x() / 6.0);  // up
      p = (frame.inverse() * Eigen::Vector3d(world.x(), world.y(), world.z() - waves)).cast<float>();
    }
    return points;
  };
  const Eigen::Isometry3d truth = planar_pose(0, 0, 0), guess = planar_pose(4.0, 0, 0);
  Submap a, b;
  a.points = sample(Eigen::Isometry3d::Identity(), 5);
  b.points = sample(truth, 6);
  CoarseToFineConfig config;
  config.switching.min_feature_density = 1;  // the direct path, whatever the mounds offer
  const SubmapFeatures target_features = extract_features(a, {}, {}), source_features = extract_features(b, {}, {});
  const OneOffPair pair = one_off_pair(*voxel_filter(a.points), *voxel_filter(b.points), config.gicp);
  const auto error_m = [&](const CoarseToFineConfig& c) {
    const PairRegistration r = register_coarse_to_fine(pair.clouds, target_features, source_features, guess, c, 1);
    EXPECT_EQ(r.path, RegistrationPath::kDirect);
    return (truth.inverse() * r.registration.source_to_target).translation().head<2>().norm();
  };
  CoarseToFineConfig from_guess_only = config;
  from_guess_only.best_basin_restarts = 0;
  EXPECT_GT(error_m(from_guess_only), 3.0) << "GICP from the guess: the neighbouring trough";
  EXPECT_LT(error_m(config), 0.3);
}

TEST(DirectRegistration, ASliverOfOverlapIsRefusedNotRegistered) {
  const SyntheticTerrain rough = SyntheticTerrain::with_mounds(41);
  const TerrainPair p = pair_of(rough, rough, planar_pose(0, 0, 0));
  // Dead reckoning puts the source 39.5 m east: a strip of a few points overlaps.
  const PairRegistration r = register_direct(one_off_pair(*p.target, *p.source, GicpConfig{}).clouds, planar_pose(39.9, 0, 0), GicpConfig{}, 0.0);
  EXPECT_FALSE(r.registration.quality.converged);
  EXPECT_EQ(rejection_of(r, planar_pose(39.9, 0, 0), {}, false).kind, RejectionKind::kNoOverlap);
}

TEST(QualityWeights, IncreaseWithInlierRatioAndOverlapAndDecreaseWithMse) {
  for (double x = 0.0; x < 1.0; x += 0.01) {
    EXPECT_LE(inlier_ratio_weight(x), inlier_ratio_weight(x + 0.01));
    EXPECT_GT(inlier_ratio_weight(x), 0.0);
  }
  for (double mse = 0.0; mse < 6.0; mse += 0.01) EXPECT_GE(overlap_mse_weight(mse), overlap_mse_weight(mse + 0.01));
  for (double n = 0; n < 20000; n += 50) EXPECT_LE(overlap_points_weight(n), overlap_points_weight(n + 50));
  EXPECT_LT(inlier_ratio_weight(0.25), inlier_ratio_weight(0.9)) << "and they do change";
  EXPECT_GT(overlap_mse_weight(0.05), overlap_mse_weight(4.0));
  EXPECT_LT(overlap_points_weight(500), overlap_points_weight(20000));

  // The information matrix follows: every diagonal entry grows with quality.
  PairRegistration worse, better;
  worse.path = better.path = RegistrationPath::kFeatureAided;
  worse.inlier_ratio = 0.3;
  better.inlier_ratio = 0.7;
  worse.registration.quality.overlap_mse_m2 = 1.0;
  better.registration.quality.overlap_mse_m2 = 0.1;
  worse.registration.quality.overlap_points = 800;
  better.registration.quality.overlap_points = 6000;
  QualityConfig diagonal;  // the information's diagonal form (without the Hessian's shape)
  diagonal.information_from_hessian = false;
  const Information6 a = quality_information(worse, diagonal), b = quality_information(better, diagonal);
  for (int k = 0; k < 6; ++k) EXPECT_LT(a(k, k), b(k, k));
}

// A direct-path registration with a good fit.
PairRegistration direct_registration(double overlap_mse_m2, std::size_t overlap_points) {
  PairRegistration direct;
  direct.path = RegistrationPath::kDirect;
  direct.inlier_ratio = 0.9;
  direct.registration.quality.overlap_mse_m2 = overlap_mse_m2;
  direct.registration.quality.overlap_points = overlap_points;
  return direct;
}

TEST(QualityWeights, ADirectEdgeKeepsOnlyTheShareOfHorizontalInformationItIsGiven) {
  const PairRegistration direct = direct_registration(0.1, 6000);
  PairRegistration featured = direct;
  featured.path = RegistrationPath::kFeatureAided;
  QualityConfig config;
  config.information_from_hessian = false;  // the share applies to the diagonal form
  const Information6 f = quality_information(featured, config);
  for (double share : {0.0, 0.1}) {
    config.direct_horizontal_share = share;
    const Information6 d = quality_information(direct, config);
    for (int k : {0, 1, 5}) EXPECT_DOUBLE_EQ(d(k, k), share * f(k, k)) << "x, y, yaw: entry " << k;
    for (int k : {2, 3, 4}) EXPECT_DOUBLE_EQ(d(k, k), f(k, k)) << "z, roll, pitch: entry " << k;
  }
}

// A depth measured where the direct path guessed, on ripples whose misfit within 5 m of the
// answer is 0.25 m², is worth no more than a 0.5 m sigma; on a flat bottom it keeps all it had.
TEST(QualityWeights, ADirectEdgesDepthIsCappedByTheReliefAroundItsAnswer) {
  PairRegistration direct = direct_registration(0.02, 12000);
  direct.uniqueness.probed = true;
  QualityConfig config;
  config.information_from_hessian = false;  // the cap applies to the diagonal form
  direct.uniqueness.local_cost_m2 = 1e-4;
  const double flat = quality_information(direct, config)(2, 2);
  EXPECT_GT(flat, 100.0);
  direct.uniqueness.local_cost_m2 = 0.25;
  EXPECT_DOUBLE_EQ(quality_information(direct, config)(2, 2), 4.0);
  config.direct_depth_from_relief = 0;
  EXPECT_DOUBLE_EQ(quality_information(direct, config)(2, 2), flat) << "off, the paper's weight";
}

TEST(QualityWeights, FromTheHessianADirectEdgeKeepsWhatItsOverlapObserved) {
  // No hand-set share: the flat pair's Hessian itself leaves x, y and yaw out.
  QualityConfig config;
  config.information_from_hessian = 1;
  config.direct_horizontal_share = 1.0;
  const Information6 best = information_from_sigmas(config.best_sigma_translation_m, config.best_sigma_rotation_rad);
  const Eigen::Isometry3d truth = planar_pose(6.0, 4.0, 8.0);
  auto shares = [&](const SyntheticTerrain& terrain) {
    const TerrainPair p = pair_of(terrain, terrain, truth);
    const PairRegistration r = register_direct(one_off_pair(*p.target, *p.source, GicpConfig{}).clouds, truth, GicpConfig{}, 1.0, true);
    EXPECT_GT(r.hessian.correspondences, 1000u);
    const Information6 information = quality_information(r, config);
    return Eigen::Matrix<double, 6, 1>(information.diagonal().cwiseQuotient(quality_weight(r) * best.diagonal()));
  };
  const Eigen::Matrix<double, 6, 1> flat = shares(SyntheticTerrain::flat());
  for (int k : {0, 1, 5}) EXPECT_LT(flat(k), 1e-3) << "flat: x, y, yaw: axis " << k;
  for (int k : {2, 3, 4}) EXPECT_GT(flat(k), 0.9) << "flat: z, roll, pitch: axis " << k;
  const Eigen::Matrix<double, 6, 1> rough = shares(SyntheticTerrain::with_mounds(21));
  for (int k = 0; k < 6; ++k) EXPECT_GT(rough(k), 0.2) << "mounds: axis " << k;

  const TerrainPair p = pair_of(SyntheticTerrain::flat(), SyntheticTerrain::flat(), truth);
  const PairRegistration without = register_direct(one_off_pair(*p.target, *p.source, GicpConfig{}).clouds, truth, GicpConfig{}, 1.0);
  EXPECT_EQ(without.hessian.correspondences, 0u) << "not computed unless asked for";
  EXPECT_THROW(quality_information(without, config), std::invalid_argument);
}

}  // namespace
}  // namespace bathyslam
