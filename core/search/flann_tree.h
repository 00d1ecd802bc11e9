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

// The tree over points of `dimensions` coordinates each, and pcl::KdTreeFLANN's two searches.
class FlannIndex {
 public:
  // `coordinates`: the finite points, `dimensions` floats each; `cloud_index`: each one's index
  // in its cloud (what the searches return).
  FlannIndex(std::vector<float> coordinates, std::vector<int> cloud_index, int dimensions);
  std::size_t size() const { return cloud_index_.size(); }
  // pcl::KdTreeFLANN::nearestKSearch: the k nearest, nearest first.
  int nearest(const float* query, int k, pcl::Indices& indices, std::vector<float>& sq_distances) const;
  // pcl::KdTreeFLANN::radiusSearch without max_nn: all within `radius`, by distance then index;
  // unless not `sorted`: then in the tree's order, which saves sorting them.
  int within(const float* query, double radius, pcl::Indices& indices, std::vector<float>& sq_distances,
             bool sorted = true) const;

 private:
  using Index = flann::KDTreeSingleIndex<flann::L2_Simple<float>>;
  template <typename ResultSet>
  void search(const float* query, int k, pcl::Indices& indices, std::vector<float>& sq_distances) const;

  std::vector<float> coordinates_;
  std::vector<int> cloud_index_;
  std::unique_ptr<Index> index_;  // null without points
};

// FlannIndex over the x and y of keypoints or the like (pcl::KdTreeFLANN<pcl::PointXY>).
FlannIndex planar_index(const std::vector<Eigen::Vector3d>& points);

// FlannIndex as the search method PCL's registration and our own callers use.
class FlannTree : public pcl::search::KdTree<pcl::PointXYZ> {
 public:
  using pcl::search::KdTree<pcl::PointXYZ>::nearestKSearch;

  // Only whole clouds (`indices` must be null): that is all GICP and our callers ask.
  void setInputCloud(const PointCloudConstPtr& cloud, const IndicesConstPtr& indices = IndicesConstPtr()) override;
  int nearestKSearch(const pcl::PointXYZ& point, int k, pcl::Indices& k_indices,
                     std::vector<float>& k_sqr_distances) const override;

 private:
  std::unique_ptr<FlannIndex> index_;
};

}  // namespace bathyslam
