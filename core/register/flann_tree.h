#pragma once
// PCL's KD-tree for point clouds (FLANN's single-index tree, 15 points a leaf, built exactly as
// pcl::KdTreeFLANN builds it), searched without the OpenMP region FLANN's batch search opens
// for every query. PCL's GICP asks one query at a time, once per point per iteration, and that
// region (a team, a barrier, a futex call, two allocations) cost more than the search itself on
// `lake`. Same tree, same search code: the same neighbours and distances, bit for bit.
#include <memory>
#include <vector>

#include <flann/algorithms/dist.h>
#include <flann/algorithms/kdtree_single_index.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

namespace bathyslam {

class FlannTree : public pcl::search::KdTree<pcl::PointXYZ> {
 public:
  using Ptr = std::shared_ptr<FlannTree>;
  using pcl::search::KdTree<pcl::PointXYZ>::nearestKSearch;

  // Only whole clouds (`indices` must be null): that is all GICP and our callers ask.
  void setInputCloud(const PointCloudConstPtr& cloud, const IndicesConstPtr& indices = IndicesConstPtr()) override;
  int nearestKSearch(const pcl::PointXYZ& point, int k, pcl::Indices& k_indices,
                     std::vector<float>& k_sqr_distances) const override;

 private:
  using Index = flann::KDTreeSingleIndex<flann::L2_Simple<float>>;
  std::vector<float> coordinates_;  // x, y, z of the finite points
  std::vector<int> cloud_index_;    // their indices in the cloud
  std::unique_ptr<Index> index_;

  template <typename ResultSet>
  void search(const pcl::PointXYZ& point, int k, pcl::Indices& k_indices, std::vector<float>& k_sqr_distances) const;
};

}  // namespace bathyslam
