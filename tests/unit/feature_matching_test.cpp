#include "core/matching/feature_matching.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "core/features/terrain_grid.h"
#include "tests/unit/synthetic_terrain.h"

namespace bathyslam {
namespace {

// Algorithm 2's matching as written, every pair within the gate scored in full: best and second
// best MSE among those that correlate, the ratio test, then mutual best matches by MSE.
std::vector<FeatureMatch> plain_matches(const std::vector<Keypoint>& source, const std::vector<Keypoint>& target,
                                        const Eigen::Isometry3d& source_to_target, const MatchConfig& config) {
  const auto one_way = [&](const std::vector<Keypoint>& queries, const std::vector<Keypoint>& indexed,
                           const Eigen::Isometry3d& query_to_indexed, const Eigen::Isometry3d& indexed_to_common) {
    std::vector<int> best(queries.size(), -1);
    std::vector<double> best_mse(queries.size(), 0);
    for (std::size_t i = 0; i < queries.size(); ++i) {
      const Eigen::Vector2f q = (query_to_indexed * queries[i].position).head<2>().cast<float>();
      double first = std::numeric_limits<double>::infinity(), second = first;
      int index = -1;
      for (std::size_t j = 0; j < indexed.size(); ++j) {
        // The gate as the matcher's radius search draws it: float positions, strictly inside.
        const Eigen::Vector2f d = q - (indexed_to_common * indexed[j].position).head<2>().cast<float>();
        if (!(d.x() * d.x() + d.y() * d.y() < static_cast<float>(config.max_distance_m * config.max_distance_m))) continue;
        if (descriptor_ncc(queries[i].descriptor, indexed[j].descriptor) < config.min_ncc) continue;
        const double mse = descriptor_mse(queries[i].descriptor, indexed[j].descriptor);
        if (mse < first) {
          second = first;
          first = mse;
          index = static_cast<int>(j);
        } else {
          second = std::min(second, mse);
        }
      }
      if (index >= 0 && first < config.ratio * second) {
        best[i] = index;
        best_mse[i] = first;
      }
    }
    return std::make_pair(best, best_mse);
  };
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  const auto [forward, forward_mse] = one_way(source, target, source_to_target, identity);
  const auto [backward, unused] = one_way(target, source, identity, source_to_target);
  std::vector<FeatureMatch> matches;
  for (std::size_t i = 0; i < forward.size(); ++i) {
    if (forward[i] >= 0 && backward[forward[i]] == static_cast<int>(i)) matches.push_back({static_cast<int>(i), forward[i], forward_mse[i]});
  }
  std::sort(matches.begin(), matches.end(), [](const FeatureMatch& a, const FeatureMatch& b) { return a.mse < b.mse; });
  return matches;
}

// Keypoints of two overlapping patches of one mound field, the source's frame shifted by `shift`.
std::pair<std::vector<Keypoint>, std::vector<Keypoint>> keypoints_of_two_views(int seed, const Eigen::Vector3d& shift,
                                                                               double noise_m,
                                                                               const KeypointConfig& keypoints = {}) {
  const SyntheticTerrain terrain = SyntheticTerrain::with_mounds(seed);
  Eigen::Isometry3d source_pose = Eigen::Isometry3d::Identity();
  source_pose.translation() = shift;
  const std::vector<Keypoint> target =
      detect_keypoints(grid_terrain(terrain.sample(Eigen::Isometry3d::Identity(), noise_m, 1), {}), keypoints);
  const std::vector<Keypoint> source = detect_keypoints(grid_terrain(terrain.sample(source_pose, noise_m, 2), {}), keypoints);
  return {source, target};
}

void expect_same_matches(const std::vector<FeatureMatch>& fast, const std::vector<FeatureMatch>& plain) {
  ASSERT_EQ(fast.size(), plain.size());
  for (std::size_t k = 0; k < fast.size(); ++k) {
    EXPECT_EQ(fast[k].source, plain[k].source);
    EXPECT_EQ(fast[k].target, plain[k].target);
    EXPECT_NEAR(fast[k].mse, plain[k].mse, 1e-12);
  }
}

// The matcher skips the scoring of neighbours that cannot beat the second best (a bound from
// each descriptor's block means and the rest's length): that must not change a single match,
// whatever the descriptor's side (3 and 5: blocks of one sample, or none).
TEST(FeatureMatching, GivesTheMatchesOfScoringEveryPairInFull) {
  int compared = 0;
  for (int seed = 1; seed <= 2; ++seed) {
    const Eigen::Vector3d shift(2.5 * seed, -1.5, 0);
    KeypointConfig keypoints;
    keypoints.descriptor_size = seed == 1 ? 11 : 5;
    const auto [source, target] = keypoints_of_two_views(seed, shift, 0.02, keypoints);
    ASSERT_GT(source.size(), 20u);
    Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
    guess.translation() = shift + Eigen::Vector3d(0.7, -0.4, 0);  // a dead-reckoning guess, off a little
    // Gates of 12 and 6 m: enough neighbours for the bound to skip most (the default 30 m spans the
    // whole patch, and scoring every pair in full under the sanitizers took two minutes).
    for (const MatchConfig config : {MatchConfig{12.0, 0.85, 0.8, 30}, MatchConfig{6.0, 0.5, 0.95, 30}}) {
      const std::vector<FeatureMatch> fast = match_features(source, target, guess, config);
      expect_same_matches(fast, plain_matches(source, target, guess, config));
      compared += static_cast<int>(fast.size());
    }
  }
  EXPECT_GT(compared, 500) << "the surveys gave matches to compare";
}

// Planar patches of one slope direction and different steepness correlate perfectly, and the
// bound equals their score but for rounding: the tightest case, on 3 x 3 descriptors too.
TEST(FeatureMatching, PlanarPatchesWhereTheBoundIsTightGiveTheFullMatches) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> steepness(0.5, 2.0), where(-3.0, 3.0);
  for (const int d : {3, 11}) {
    Eigen::VectorXf slope(d * d);
    for (int k = 0; k < d * d; ++k) slope[k] = static_cast<float>(0.1 * (k % d) + 0.03 * (k / d));
    slope.array() -= slope.mean();
    std::vector<Keypoint> source(40), target(40);
    for (std::size_t i = 0; i < source.size(); ++i) {
      for (Keypoint* k : {&source[i], &target[i]}) {
        k->position = Eigen::Vector3d(where(rng), where(rng), 10);
        k->descriptor = static_cast<float>(steepness(rng)) * slope;
      }
    }
    const MatchConfig config{8.0, 0.5, 0.999, 3};
    expect_same_matches(match_features(source, target, Eigen::Isometry3d::Identity(), config),
                        plain_matches(source, target, Eigen::Isometry3d::Identity(), config));
  }
}

// The same ground seen from a frame 6 m away: the matches join keypoints at the same place.
TEST(FeatureMatching, JoinsKeypointsOfTheSameGround) {
  const Eigen::Vector3d shift(6.0, 3.0, 0);
  const auto [source, target] = keypoints_of_two_views(5, shift, 0.01);
  Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
  guess.translation() = shift + Eigen::Vector3d(1.0, 1.0, 0);
  const std::vector<FeatureMatch> matches = match_features(source, target, guess);
  ASSERT_GE(matches.size(), 10u);
  int right = 0;
  for (const FeatureMatch& m : matches) {
    const Eigen::Vector3d source_in_target = source[m.source].position + shift;
    if ((source_in_target - target[m.target].position).head<2>().norm() < 1.0) ++right;
  }
  EXPECT_GE(right, 0.9 * static_cast<double>(matches.size())) << right << " of " << matches.size();
}

}  // namespace
}  // namespace bathyslam
