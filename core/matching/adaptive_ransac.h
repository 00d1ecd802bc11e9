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
  // Periodic seabeds (sand waves, parallel ridges) give several alignments that each explain a
  // share of the matches. After the winner, RANSAC runs again on the matches it left out; a
  // competing transform that places some matched keypoint at least this far from where the
  // winner does is a distinct solution, and its support is reported (acceptance judges it).
  bool find_competitor = true;
  double competitor_separation_m = 3.0;
  template <typename Field>
  void fields(Field&& field) {
    field("max_iterations", max_iterations, 1, 1000000);
    field("initial_threshold_m", initial_threshold_m, 0.01, 1e5);
    field("sample_size", sample_size, 3, 100);
    field("target_inlier_ratio", target_inlier_ratio, 0.01, 1);
    field("min_inliers", min_inliers, 3, 100000);
    field("mad_scale", mad_scale, 0.1, 100);
    field("min_threshold_m", min_threshold_m, 0.001, 1e5);
    field("seed", seed, 0, 9007199254740992.0);  // 2^53: every integer a double holds
    field("find_competitor", find_competitor, 0, 1);
    field("competitor_separation_m", competitor_separation_m, 0.01, 1e5);
  }
};

struct RansacResult {
  Eigen::Isometry3d source_to_target = Eigen::Isometry3d::Identity();
  std::vector<int> inliers;  // indices into the correspondences
  double threshold_m = 0;    // the adaptive threshold at the end
  double inlier_ratio = 0;   // inliers over correspondences
  int iterations = 0;
  // The best distinct alternative (find_competitor): its inliers among the matches the winner
  // left out, and how far apart the two put the matched keypoints (largest displacement).
  int competitor_inliers = 0;
  double competitor_separation_m = 0;
};

// `source[i]` corresponds to `target[i]`; the order is PROSAC's (best first). Deterministic for
// a given seed.
RansacResult adaptive_ransac(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target,
                             const RansacConfig& config = {});

}  // namespace bathyslam
