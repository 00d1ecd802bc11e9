#include "core/matching/feature_matching.h"

#include <algorithm>
#include <limits>

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>

namespace bathyslam {
namespace {

struct BestMatch {
  int index = -1;
  double mse = std::numeric_limits<double>::infinity();
};

// For each query keypoint (positions already in the indexed set's frame), its best match among
// the indexed keypoints within the gate, if it passes correlation and the ratio test.
std::vector<BestMatch> one_way(const std::vector<Keypoint>& queries, const std::vector<Eigen::Vector3d>& query_positions,
                               const std::vector<Keypoint>& indexed, const std::vector<Eigen::Vector3d>& indexed_positions,
                               const MatchConfig& config) {
  std::vector<BestMatch> best(queries.size());
  if (indexed.empty()) return best;
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXY>>();
  for (const Eigen::Vector3d& p : indexed_positions) {
    pcl::PointXY q;
    q.x = static_cast<float>(p.x());
    q.y = static_cast<float>(p.y());
    cloud->push_back(q);
  }
  pcl::KdTreeFLANN<pcl::PointXY> tree;
  tree.setInputCloud(cloud);
  std::vector<int> near;
  std::vector<float> sq_distances;
  for (std::size_t i = 0; i < queries.size(); ++i) {
    pcl::PointXY q;
    q.x = static_cast<float>(query_positions[i].x());
    q.y = static_cast<float>(query_positions[i].y());
    tree.radiusSearch(q, config.max_distance_m, near, sq_distances);
    double second = std::numeric_limits<double>::infinity();
    for (int j : near) {
      if (descriptor_ncc(queries[i].descriptor, indexed[j].descriptor) < config.min_ncc) continue;
      const double mse = descriptor_mse(queries[i].descriptor, indexed[j].descriptor);
      if (mse < best[i].mse) {
        second = best[i].mse;
        best[i] = {j, mse};
      } else {
        second = std::min(second, mse);
      }
    }
    // A repetitive terrain offers two near-equal matches: trust neither.
    if (best[i].index >= 0 && !(best[i].mse < config.ratio * second)) best[i] = {};
  }
  return best;
}

}  // namespace

std::vector<FeatureMatch> match_features(const std::vector<Keypoint>& source, const std::vector<Keypoint>& target,
                                         const Eigen::Isometry3d& source_to_target, const MatchConfig& config) {
  std::vector<Eigen::Vector3d> source_in_target, target_in_target;
  for (const Keypoint& k : source) source_in_target.push_back(source_to_target * k.position);
  for (const Keypoint& k : target) target_in_target.push_back(k.position);
  const std::vector<BestMatch> forward = one_way(source, source_in_target, target, target_in_target, config);
  const std::vector<BestMatch> backward = one_way(target, target_in_target, source, source_in_target, config);

  std::vector<FeatureMatch> matches;
  for (std::size_t i = 0; i < forward.size(); ++i) {
    const int j = forward[i].index;
    if (j >= 0 && backward[j].index == static_cast<int>(i)) matches.push_back({static_cast<int>(i), j, forward[i].mse});
  }
  // Mutual best matches are already one-to-one; sorting gives PROSAC its order.
  std::sort(matches.begin(), matches.end(), [](const FeatureMatch& a, const FeatureMatch& b) { return a.mse < b.mse; });
  return matches;
}

}  // namespace bathyslam
