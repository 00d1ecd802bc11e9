// Our GICP (gicp_cloud, gicp_factor, gicp_solver) against the truth and against PCL's GICP.
#include "core/register/gicp_solver.h"

#include <gtest/gtest.h>

#include <numeric>
#include <random>

#include "core/candidates/candidates.h"
#include "core/register/coarse_to_fine.h"
#include "tests/unit/synthetic_terrain.h"
#include "tests/unit/true_submaps.h"

namespace bathyslam {
namespace {

double yaw_deg(const Eigen::Isometry3d& t) {
  return std::atan2(t.rotation()(1, 0), t.rotation()(0, 0)) * 180 / M_PI;
}

double angle_deg(const Eigen::Isometry3d& t) { return Eigen::AngleAxisd(t.rotation()).angle() * 180 / M_PI; }

// Soundings every `spacing_m` over the world rectangle [lo, hi] of `terrain`, in the frame whose
// pose in the world is `frame` (z down).
Cloud::Ptr soundings(const SyntheticTerrain& terrain, const Eigen::Isometry3d& frame, const Eigen::Vector2d& lo,
                     const Eigen::Vector2d& hi, double spacing_m, double noise_m, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m > 0 ? noise_m : 1e-12);
  auto cloud = std::make_shared<Cloud>();
  for (double x = lo.x(); x <= hi.x(); x += spacing_m) {
    for (double y = lo.y(); y <= hi.y(); y += spacing_m) {
      const Eigen::Vector3f p =
          (frame.inverse() * Eigen::Vector3d(x, y, -(terrain.elevation({x, y}) + noise(rng)))).cast<float>();
      cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    }
  }
  return cloud;
}

// Two 30 x 40 m submaps of mounds overlapping by 20 x 40 m, the source turned 20 degrees.
struct MoundPair {
  Cloud::Ptr target, source;
  Eigen::Isometry3d truth;  // source to target
};

MoundPair mound_pair(const SyntheticTerrain& terrain, double noise_m = 0.02) {
  const Eigen::Isometry3d target_frame = planar_pose(15, 20, 0), source_frame = planar_pose(25, 20, 20);
  MoundPair p;
  p.truth = target_frame.inverse() * source_frame;
  p.target = soundings(terrain, target_frame, {0, 0}, {30, 40}, 0.25, noise_m, 1);
  p.source = soundings(terrain, source_frame, {10.1, 0.1}, {40, 40}, 0.25, noise_m, 2);
  return p;
}

// 1.5 m, 1 m and 3 degrees of yaw off the truth.
Eigen::Isometry3d off(const Eigen::Isometry3d& truth) {
  return planar_pose(1.5, 1.0, 3.0) * truth;
}

GicpConfig ours(GicpConfig config = {}) {
  config.engine = 1;
  return config;
}

GicpConfig pcl_gicp(GicpConfig config) {
  config.engine = 0;
  return config;
}

GicpConfig large_offset() {  // as the feature-aided path refines
  GicpConfig config;
  config.about_centroid = 1;
  config.refine_correspondence_m = 1.0;
  return config;
}

TEST(OwnGicp, RecoversAKnownOffsetOnMounds) {
  const MoundPair p = mound_pair(SyntheticTerrain::with_mounds(7, 14));
  const Eigen::Isometry3d guess = off(p.truth);
  for (const GicpConfig& config : {ours(), ours(large_offset())}) {
    const PairRegistration r = register_direct(one_off_pair(*p.target, *p.source, config).clouds, guess, config, 1.0);
    const Eigen::Isometry3d error = p.truth.inverse() * r.registration.source_to_target;
    EXPECT_TRUE(r.registration.quality.converged);
    EXPECT_LT(error.translation().norm(), 0.05) << "about_centroid " << config.about_centroid << ": "
                                                << error.translation().transpose();
    EXPECT_LT(std::abs(yaw_deg(error)), 0.1) << "about_centroid " << config.about_centroid;
    EXPECT_LT(angle_deg(error), 0.15);
    EXPECT_GT(r.registration.quality.fitness, 0.9);
    EXPECT_LT(r.registration.quality.overlap_mse_m2, 0.04);  // nearest soundings, 0.25 m apart
  }
}

// The associator's shortcut (keep a neighbour the triangle inequality proves unchanged) gives
// exactly what a brute-force search gives, over moves from centimetres to a metre and back.
TEST(OwnGicp, AssociatorFindsTheBruteForceNeighbours) {
  const MoundPair p = mound_pair(SyntheticTerrain::with_mounds(7, 14));
  const auto target = prepare_gicp_cloud(*p.target, GicpConfig{});
  const auto source = prepare_gicp_cloud(*p.source, GicpConfig{});
  const GicpOverlap overlap = gicp_overlap(*target, *source, p.truth, 1.0);
  ASSERT_GT(overlap.target_points, 1000u);
  ASSERT_LT(overlap.target_points, target->points.size()) << "the mask must matter";
  const double gate_m = 1.0;
  Associator associator(*target, *source, overlap, gate_m);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> step(0.0, 1.0);
  Eigen::Isometry3d pose = off(p.truth);
  std::size_t compared = 0, associated = 0;
  for (int move = 0; move < 24; ++move) {
    const double size_m = move < 12 ? 0.003 : 0.3;  // creeping, then jumping
    pose = planar_pose(size_m * step(rng), size_m * step(rng), 2 * size_m * step(rng)) * pose;
    const std::vector<GicpCorrespondence> found = associator.at(pose, 1);
    associated += found.size();
    std::vector<int> neighbour(source->points.size(), -1);
    for (const GicpCorrespondence& c : found) neighbour[c.source] = static_cast<int>(c.target);
    // Brute force on every fifth overlap point (all of them would take seconds).
    const Eigen::Isometry3f moved_by = pose.cast<float>();
    for (std::size_t k = 0; k < overlap.source_points.size(); k += 5) {
      const Eigen::Vector3f x = moved_by * source->points[overlap.source_points[k]];
      float best = static_cast<float>(gate_m * gate_m);
      int nearest = -1;
      for (std::size_t j = 0; j < target->points.size(); ++j) {
        const float d = (x - target->points[j]).squaredNorm();
        if (overlap.target_allowed[j] && d <= best) best = d, nearest = static_cast<int>(j);
      }
      const int got = neighbour[overlap.source_points[k]];
      ASSERT_EQ(got >= 0, nearest >= 0) << "move " << move << ", point " << k;
      // Equidistant neighbours may come in either order: the distance is what must agree.
      if (got >= 0) {
        ASSERT_NEAR((x - target->points[got]).squaredNorm(), best, 1e-6) << "move " << move;
      }
      ++compared;
    }
  }
  EXPECT_GT(compared, 10000u);
  EXPECT_LT(associator.searches(), associated * 9 / 10) << "the shortcut hardly applied";
}

// A pass that turns further from its start than max_turn_deg has left its basin: it ends, not
// converged; the same pass within the limit converges.
TEST(OwnGicp, APassThatTurnsBeyondTheLimitDoesNotConverge) {
  const MoundPair p = mound_pair(SyntheticTerrain::with_mounds(7, 14));
  GicpConfig config = ours();
  const PairRegistration within = register_direct(one_off_pair(*p.target, *p.source, config).clouds, off(p.truth), config, 1.0);
  EXPECT_TRUE(within.registration.quality.converged);
  config.max_turn_deg = 1.0;  // the guess is 3 degrees off
  const PairRegistration beyond = register_direct(one_off_pair(*p.target, *p.source, config).clouds, off(p.truth), config, 1.0);
  EXPECT_FALSE(beyond.registration.quality.converged);
}

// A job being stopped ends its registrations within an iteration: not converged, at the guess.
TEST(OwnGicp, ACancelledRegistrationStopsAtOnce) {
  const MoundPair p = mound_pair(SyntheticTerrain::with_mounds(7, 14));
  const auto target = prepare_gicp_cloud(*p.target, GicpConfig{}), source = prepare_gicp_cloud(*p.source, GicpConfig{});
  std::atomic<bool> cancel = false;
  const PairRegistration running =
      register_direct(PairClouds{target.get(), source.get(), nullptr, nullptr, &cancel}, off(p.truth), ours(), 1.0);
  EXPECT_TRUE(running.registration.quality.converged);
  cancel = true;
  const PairRegistration stopped =
      register_direct(PairClouds{target.get(), source.get(), nullptr, nullptr, &cancel}, off(p.truth), ours(), 1.0);
  EXPECT_FALSE(stopped.registration.quality.converged);
  EXPECT_TRUE(stopped.registration.source_to_target.isApprox(off(p.truth)));
}

TEST(OwnGicp, AgreesWithPclOnAnAdjacentLinePairOfASimulatedSurvey) {
  const SubmapSet set = true_small_submaps(4);
  const std::vector<Eigen::Isometry3d> poses = poses_of(set);
  // On a flat bottom the horizontal answer is wherever each solver stops on a flat cost.
  const std::optional<CandidatePair> found = roughest_adjacent_pair(set);
  ASSERT_TRUE(found);
  const CandidatePair pair = *found;
  const Eigen::Isometry3d truth = poses[pair.target].inverse() * poses[pair.source];
  const Eigen::Isometry3d guess = off(truth);
  const Cloud::Ptr target = voxel_filter(set.submaps[pair.target].points);
  const Cloud::Ptr source = voxel_filter(set.submaps[pair.source].points);

  const PairRegistration reference = register_direct(pcl_pair(*target, *source), guess, pcl_gicp(large_offset()), 1.0);
  const PairRegistration own = register_direct(one_off_pair(*target, *source, ours(large_offset())).clouds, guess, ours(large_offset()), 1.0);
  ASSERT_TRUE(reference.registration.quality.converged);
  ASSERT_TRUE(own.registration.quality.converged);
  const Eigen::Isometry3d apart = reference.registration.source_to_target.inverse() * own.registration.source_to_target;
  EXPECT_LT(apart.translation().norm(), 0.05) << apart.translation().transpose();
  EXPECT_LT(angle_deg(apart), 0.1);
  // Quality is measured the same way on the same crop; ours estimates it, and the overlap's
  // centroid, from its sample (gicp_factor.h, sampled_overlap_quality).
  EXPECT_LT((own.anchor - reference.anchor).norm(), 0.1);
  EXPECT_NEAR(own.registration.quality.fitness, reference.registration.quality.fitness, 0.02);
  EXPECT_NEAR(static_cast<double>(own.registration.quality.overlap_points),
              static_cast<double>(reference.registration.quality.overlap_points),
              0.03 * static_cast<double>(reference.registration.quality.overlap_points));
  EXPECT_NEAR(own.registration.quality.overlap_mse_m2, reference.registration.quality.overlap_mse_m2,
              0.1 * reference.registration.quality.overlap_mse_m2);
  // And ours is at least as close to the truth.
  const double reference_error = (truth.inverse() * reference.registration.source_to_target).translation().norm();
  const double own_error = (truth.inverse() * own.registration.source_to_target).translation().norm();
  EXPECT_LT(own_error, reference_error + 0.02);
}

TEST(OwnGicp, HessianIsTheCostsOnTheSameCorrespondences) {
  // Margins wide enough that the crop keeps both clouds whole: the PCL-built terms then use the
  // same neighbourhoods for the covariances.
  const MoundPair p = mound_pair(SyntheticTerrain::with_mounds(3, 14));
  const Eigen::Vector3d anchor(5, 2, 10);
  GicpConfig every_sounding;  // as the PCL-built terms
  every_sounding.soundings_per_sample = 1;
  const auto target = prepare_gicp_cloud(*p.target, every_sounding), source = prepare_gicp_cloud(*p.source, every_sounding);
  const GicpOverlap overlap = gicp_overlap(*target, *source, p.truth, 1000.0);
  ASSERT_EQ(overlap.source_points.size(), p.source->size());
  const GicpLinearisation lin =
      linearise_gicp(*target, *source, overlap, p.truth, p.truth * anchor, 3.0, 1, /*with_regularisation=*/true);
  const GicpHessian reference = gicp_hessian(*p.target, *p.source, p.truth, anchor, GicpConfig{});
  EXPECT_EQ(lin.correspondences, reference.correspondences);
  EXPECT_LT((lin.hessian - reference.hessian).norm(), 1e-3 * reference.hessian.norm());
  EXPECT_LT((lin.regularisation - reference.regularisation).norm(), 1e-6 * reference.regularisation.norm());
  // register_direct hands the same Hessian on at its answer.
  const PairRegistration r = register_direct(one_off_pair(*p.target, *p.source, ours()).clouds, p.truth, ours(), 1.0, /*with_hessian=*/true);
  EXPECT_GT(r.hessian.correspondences, 0u);
  EXPECT_TRUE(r.hessian.hessian.allFinite());
  EXPECT_GT(r.hessian.hessian.determinant(), 0);
}

TEST(OwnGicp, OneOrTwoThreadsGiveTheSameNormalEquations) {
  const MoundPair p = mound_pair(SyntheticTerrain::with_mounds(5, 14));
  const auto target = prepare_gicp_cloud(*p.target, GicpConfig{}), source = prepare_gicp_cloud(*p.source, GicpConfig{});
  const GicpOverlap overlap = gicp_overlap(*target, *source, off(p.truth), 1.0);
  const GicpLinearisation one = linearise_gicp(*target, *source, overlap, off(p.truth), Eigen::Vector3d::Zero(), 3.0, 1);
  const GicpLinearisation two = linearise_gicp(*target, *source, overlap, off(p.truth), Eigen::Vector3d::Zero(), 3.0, 2);
  EXPECT_EQ(one.correspondences, two.correspondences);
  EXPECT_LT((one.hessian - two.hessian).norm(), 1e-9 * one.hessian.norm());
  EXPECT_LT((one.gradient - two.gradient).norm(), 1e-9 * one.gradient.norm());
}

TEST(OwnGicp, CovariancesAreFlatAlongATiltedPlane) {
  Cloud plane;
  const Eigen::Vector3d normal = Eigen::Vector3d(0.2, -0.1, 1).normalized();
  for (double x = -5; x <= 5; x += 0.25) {
    for (double y = -5; y <= 5; y += 0.25) {
      const double z = -(normal.x() * x + normal.y() * y) / normal.z();
      plane.push_back(pcl::PointXYZ(x, y, z));
    }
  }
  const auto prepared = prepare_gicp_cloud(plane, GicpConfig{});
  std::vector<uint32_t> all(prepared->points.size());
  std::iota(all.begin(), all.end(), 0u);
  prepared->ensure_normals(all, 2);
  for (std::size_t i = 0; i < all.size(); i += 37) {
    const Eigen::Matrix3d c = prepared->covariance(i);
    EXPECT_NEAR(normal.dot(c * normal), 1e-3, 1e-5);
    EXPECT_NEAR(c.trace(), 2.001, 1e-5);
  }
}

TEST(OwnGicp, EmptyOrTinyCloudsDoNotConverge) {
  const MoundPair p = mound_pair(SyntheticTerrain::with_mounds(7, 14));
  const Cloud empty;
  Cloud tiny;
  for (int i = 0; i < 10; ++i) tiny.push_back((*p.source)[i * 100]);
  for (const Cloud* source : std::vector<const Cloud*>{&empty, &tiny}) {
    const PairRegistration r = register_direct(one_off_pair(*p.target, *source, ours()).clouds, p.truth, ours(), 1.0, true);
    EXPECT_FALSE(r.registration.quality.converged);
    EXPECT_TRUE(r.registration.source_to_target.isApprox(p.truth)) << "the guess comes back";
    EXPECT_EQ(r.hessian.correspondences, 0u);
  }
  const PairRegistration both_empty = register_direct(one_off_pair(empty, empty, ours()).clouds, p.truth, ours(), 1.0);
  EXPECT_FALSE(both_empty.registration.quality.converged);
  // Clouds that do not overlap under the guess: nothing to register.
  const PairRegistration apart = register_direct(one_off_pair(*p.target, *p.source, ours()).clouds, planar_pose(500, 0, 0) * p.truth, ours(), 1.0);
  EXPECT_FALSE(apart.registration.quality.converged);
}

// Started 10 m off on four sparse mounds, a pass slides for over a hundred iterations at a cost
// that hardly falls, to an answer as wrong as where it was after a few dozen: the stall rule
// ends it there, converged as at the iteration limit.
TEST(OwnGicp, APassWhoseCostStopsFallingEndsOnTheStallRule) {
  const MoundPair p = mound_pair(SyntheticTerrain::with_mounds(9, 4), 0.05);
  GicpConfig every_sounding;  // the sample slides for fewer iterations: the case is built on all
  every_sounding.soundings_per_sample = 1;
  const auto target = prepare_gicp_cloud(*p.target, every_sounding), source = prepare_gicp_cloud(*p.source, every_sounding);
  const Eigen::Isometry3d guess = planar_pose(10, 5, 2) * p.truth;
  const GicpOverlap overlap = gicp_overlap(*target, *source, guess, 1.0);
  const Eigen::Vector3d anchor = source_centroid(*source, overlap);
  auto pass = [&](int stall_iterations) {
    Associator associator(*target, *source, overlap, 3.0);
    return gauss_newton_gicp(*target, *source, associator, guess, guess * anchor, anchor, 1e-3, 300, stall_iterations,
                             GicpConfig{}.min_observed_share, M_PI, 1);
  };
  const GaussNewtonPass sliding = pass(0), stalled = pass(40);
  ASSERT_GT(sliding.iterations, 100) << "the case no longer slides";
  EXPECT_TRUE(stalled.converged);
  EXPECT_LT(stalled.iterations, sliding.iterations / 2);
  const double slid_m = (p.truth.inverse() * sliding.source_to_target).translation().norm();
  const double stalled_m = (p.truth.inverse() * stalled.source_to_target).translation().norm();
  EXPECT_GT(std::min(slid_m, stalled_m), 5.0) << "neither pass found the answer";
  EXPECT_NEAR(stalled_m, slid_m, 1.0);
}

TEST(OwnGicp, AFlatBottomPinsDepthAndStaysFinite) {
  const MoundPair p = mound_pair(SyntheticTerrain::flat(), 0.01);
  Eigen::Isometry3d guess = off(p.truth);
  guess.translation().z() += 0.4;  // depth is what a flat bottom observes
  const PairRegistration r = register_direct(one_off_pair(*p.target, *p.source, ours()).clouds, guess, ours(), 1.0);
  EXPECT_TRUE(r.registration.quality.converged);
  EXPECT_TRUE(r.registration.source_to_target.matrix().allFinite());
  const Eigen::Isometry3d error = p.truth.inverse() * r.registration.source_to_target;
  EXPECT_LT(std::abs((r.registration.source_to_target * r.anchor - p.truth * r.anchor).z()), 0.02);
  EXPECT_LT(std::abs(error.rotation()(2, 0)) + std::abs(error.rotation()(2, 1)), 2e-3) << "roll and pitch pinned";
}

TEST(GicpCloudCache, PreparesEachSubmapOnce) {
  const MoundPair p = mound_pair(SyntheticTerrain::with_mounds(7, 14));
  const std::vector<Cloud::Ptr> clouds{p.target, p.source};
  GicpCloudCache cache(clouds, GicpConfig{});
  const GicpCloud& first = cache.at(1);
  EXPECT_EQ(&first, &cache.at(1));
  EXPECT_EQ(first.soundings.size(), p.source->size());
  EXPECT_LT(first.points.size(), p.source->size() / 2) << "the sample";
  EXPECT_EQ(first.neighbours, 20);
}

TEST(GicpCloudCache, TrimDropsTheSubmapsUsedLongestAgo) {
  const MoundPair p = mound_pair(SyntheticTerrain::with_mounds(7, 14));
  const std::vector<Cloud::Ptr> clouds{p.target, p.source, p.target};
  GicpCloudCache cache(clouds, GicpConfig{});
  const std::size_t one = cache.at(0).bytes();
  cache.at(1);
  cache.at(2);
  cache.at(0);  // now the most recent: 1 was used longest ago, then 2
  const std::size_t all = cache.bytes();
  cache.trim(all);
  EXPECT_EQ(cache.bytes(), all) << "within the budget nothing goes";
  cache.trim(all - 1);
  EXPECT_EQ(cache.bytes(), all - prepare_gicp_cloud(*p.source, GicpConfig{})->bytes()) << "submap 1 goes first";
  cache.trim(one);  // then 2, used before 0
  EXPECT_EQ(cache.bytes(), one);
  EXPECT_EQ(cache.at(2).soundings.size(), p.target->size()) << "a dropped submap is prepared again on use";
}

}  // namespace
}  // namespace bathyslam
