#include "core/search/flann_tree.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bathyslam {

FlannIndex::FlannIndex(std::vector<float> coordinates, std::vector<int> cloud_index, int dimensions)
    : coordinates_(std::move(coordinates)), cloud_index_(std::move(cloud_index)) {
  if (cloud_index_.empty()) return;
  index_ = std::make_unique<Index>(
      flann::Matrix<float>(coordinates_.data(), cloud_index_.size(), static_cast<std::size_t>(dimensions)),
      flann::KDTreeSingleIndexParams(15));  // pcl::KdTreeFLANN's
  index_->buildIndex();
}

int FlannIndex::nearest(const float* query, int k, pcl::Indices& indices, std::vector<float>& sq_distances) const {
  k = index_ == nullptr ? 0 : std::min(k, static_cast<int>(size()));
  indices.resize(static_cast<std::size_t>(std::max(k, 0)));
  sq_distances.resize(indices.size());
  if (k <= 0) return 0;
  // FLANN's choice of result set (KNN_HEAP_THRESHOLD); the simple one for GICP's 20 and 1.
  if (k > KNN_HEAP_THRESHOLD) {
    search<flann::KNNResultSet2<float>>(query, k, indices, sq_distances);
  } else {
    search<flann::KNNSimpleResultSet<float>>(query, k, indices, sq_distances);
  }
  return k;
}

template <typename ResultSet>
void FlannIndex::search(const float* query, int k, pcl::Indices& indices, std::vector<float>& sq_distances) const {
  ResultSet result(static_cast<std::size_t>(k));
  index_->findNeighbors(result, query, flann::SearchParams(-1, 0.0f));  // KdTreeFLANN's param_k_
  std::vector<std::size_t> at(static_cast<std::size_t>(k), 0);
  result.copy(at.data(), sq_distances.data(), std::min(result.size(), at.size()), true);
  for (std::size_t j = 0; j < at.size(); ++j) indices[j] = cloud_index_[at[j]];
}

int FlannIndex::within(const float* query, double radius, pcl::Indices& indices, std::vector<float>& sq_distances,
                       bool sorted) const {
  indices.clear();
  sq_distances.clear();
  if (index_ == nullptr) return 0;
  flann::RadiusResultSet<float> result(static_cast<float>(radius * radius));
  index_->findNeighbors(result, query, flann::SearchParams(-1, 0.0f, sorted));  // KdTreeFLANN's param_radius_
  const std::size_t n = result.size();
  std::vector<std::size_t> at(n);
  sq_distances.resize(n);
  if (n > 0) result.copy(at.data(), sq_distances.data(), n, sorted);
  indices.resize(n);
  for (std::size_t j = 0; j < n; ++j) indices[j] = cloud_index_[at[j]];
  return static_cast<int>(n);
}

FlannIndex planar_index(const std::vector<Eigen::Vector3d>& points) {
  std::vector<float> coordinates;
  std::vector<int> cloud_index;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto x = static_cast<float>(points[i].x()), y = static_cast<float>(points[i].y());
    if (!std::isfinite(x) || !std::isfinite(y)) continue;  // pcl::KdTreeFLANN skips them too
    coordinates.insert(coordinates.end(), {x, y});
    cloud_index.push_back(static_cast<int>(i));
  }
  return FlannIndex(std::move(coordinates), std::move(cloud_index), 2);
}

void FlannTree::setInputCloud(const PointCloudConstPtr& cloud, const IndicesConstPtr& indices) {
  if (indices != nullptr) throw std::invalid_argument("FlannTree: indices are not supported");
  input_ = cloud;
  indices_ = indices;
  index_.reset();
  if (cloud == nullptr) return;
  // pcl::KdTreeFLANN's convertCloudToArray: finite points only, in cloud order.
  std::vector<float> coordinates;
  std::vector<int> cloud_index;
  coordinates.reserve(3 * cloud->size());
  cloud_index.reserve(cloud->size());
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    const pcl::PointXYZ& p = (*cloud)[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    coordinates.insert(coordinates.end(), {p.x, p.y, p.z});
    cloud_index.push_back(static_cast<int>(i));
  }
  index_ = std::make_unique<FlannIndex>(std::move(coordinates), std::move(cloud_index), 3);
}

int FlannTree::nearestKSearch(const pcl::PointXYZ& point, int k, pcl::Indices& k_indices,
                              std::vector<float>& k_sqr_distances) const {
  const float query[3] = {point.x, point.y, point.z};
  if (index_ == nullptr) {
    k_indices.clear();
    k_sqr_distances.clear();
    return 0;
  }
  return index_->nearest(query, k, k_indices, k_sqr_distances);
}

}  // namespace bathyslam
