#pragma once
// matching (Algorithm 3): a rigid transform from feature matches by RANSAC with PROSAC ordering,
// a MAD-based adaptive inlier threshold, and a least-squares refit on all inliers.
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

namespace bathyslam {

struct RansacConfig {  // Table 1 (b)
  int max_iterations = 3000;
  double initial_threshold_m = 3.0;
  int sample_size = 3;
  double target_inlier_ratio = 0.8;  // stop early once this share of the matches agrees
  int min_inliers = 6;               // below: no refit, and the estimate is not trusted
  double mad_scale = 3.0;            // threshold = median + mad_scale * 1.4826 * MAD of inlier errors
  double min_threshold_m = 0.5;      // the grid's keypoint localisation: never tighter than this
  uint64_t seed = 1;
};

struct RansacResult {
  Eigen::Isometry3d source_to_target = Eigen::Isometry3d::Identity();
  std::vector<int> inliers;  // indices into the correspondences
  double threshold_m = 0;    // the adaptive threshold at the end
  double inlier_ratio = 0;   // inliers over correspondences
  int iterations = 0;
};

// `source[i]` corresponds to `target[i]`; the order is PROSAC's (best first). Deterministic for
// a given seed.
RansacResult adaptive_ransac(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target,
                             const RansacConfig& config = {});

}  // namespace bathyslam
