#pragma once
// matching (Algorithm 2): keypoint correspondences between two submaps, gated by distance in
// dead-reckoning-predicted coordinates, descriptor correlation, a ratio test and a
// bidirectional, one-to-one check.
#include <vector>

#include <Eigen/Geometry>

#include "core/features/tsd_keypoints.h"

namespace bathyslam {

struct MatchConfig {  // Table 1 (b)
  double max_distance_m = 30.0;  // spatial gate, DR-predicted
  double min_ncc = 0.85;
  double ratio = 0.8;            // best MSE below this fraction of the second best
  int min_matches = 30;          // fewer: the pair falls back to direct registration
  template <typename Field>
  void fields(Field&& field) {
    field("max_distance_m", max_distance_m, 0.1, 1e5);
    field("min_ncc", min_ncc, -1, 1);
    field("ratio", ratio, 0.01, 1);
    field("min_matches", min_matches, 3, 100000);
  }
};

struct FeatureMatch {
  int source = 0;  // index into the source keypoints
  int target = 0;  // index into the target keypoints
  double mse = 0;  // descriptor MSE (m^2): lower is better, PROSAC's ordering
};

// Matches sorted by MSE, best first. `source_to_target` is the DR-predicted relative pose.
std::vector<FeatureMatch> match_features(const std::vector<Keypoint>& source, const std::vector<Keypoint>& target,
                                         const Eigen::Isometry3d& source_to_target, const MatchConfig& config = {});

}  // namespace bathyslam
