#include "core/register/flann_tree.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bathyslam {

void FlannTree::setInputCloud(const PointCloudConstPtr& cloud, const IndicesConstPtr& indices) {
  if (indices != nullptr) throw std::invalid_argument("FlannTree: indices are not supported");
  input_ = cloud;
  indices_ = indices;
  coordinates_.clear();
  cloud_index_.clear();
  index_.reset();
  if (cloud == nullptr) return;
  // pcl::KdTreeFLANN's convertCloudToArray: finite points only, in cloud order.
  coordinates_.reserve(3 * cloud->size());
  cloud_index_.reserve(cloud->size());
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const pcl::PointXYZ& p = (*cloud)[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    coordinates_.insert(coordinates_.end(), {p.x, p.y, p.z});
    cloud_index_.push_back(static_cast<int>(i));
  }
  if (cloud_index_.empty()) return;
  index_ = std::make_unique<Index>(flann::Matrix<float>(coordinates_.data(), cloud_index_.size(), 3),
                                   flann::KDTreeSingleIndexParams(15));
  index_->buildIndex();
}

int FlannTree::nearestKSearch(const pcl::PointXYZ& point, int k, pcl::Indices& k_indices,
                              std::vector<float>& k_sqr_distances) const {
  // pcl::KdTreeFLANN::nearestKSearch, with the body of FLANN's batch loop for one query.
  k = index_ == nullptr ? 0 : std::min(k, static_cast<int>(cloud_index_.size()));
  k_indices.resize(static_cast<std::size_t>(std::max(k, 0)));
  k_sqr_distances.resize(k_indices.size());
  if (k <= 0) return 0;
  // FLANN's choice of result set (KNN_HEAP_THRESHOLD); the simple one for GICP's 20 and 1.
  if (k > KNN_HEAP_THRESHOLD) {
    search<flann::KNNResultSet2<float>>(point, k, k_indices, k_sqr_distances);
  } else {
    search<flann::KNNSimpleResultSet<float>>(point, k, k_indices, k_sqr_distances);
  }
  return k;
}

template <typename ResultSet>
void FlannTree::search(const pcl::PointXYZ& point, int k, pcl::Indices& k_indices,
                       std::vector<float>& k_sqr_distances) const {
  const float query[3] = {point.x, point.y, point.z};
  ResultSet result(static_cast<std::size_t>(k));
  index_->findNeighbors(result, query, flann::SearchParams(-1, 0.0f));  // KdTreeFLANN's param_k_
  std::vector<std::size_t> at(static_cast<std::size_t>(k), 0);
  result.copy(at.data(), k_sqr_distances.data(), std::min(result.size(), at.size()), true);
  for (std::size_t j = 0; j < at.size(); ++j) k_indices[j] = cloud_index_[at[j]];
}

}  // namespace bathyslam
