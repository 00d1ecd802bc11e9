#include "core/register/point_tree.h"

namespace bathyslam {
namespace {

// nanoflann result set for one nearest neighbour that skips masked points and starts with the
// correspondence gate as its bound, so the search prunes everything beyond the gate.
class MaskedNearest {
 public:
  MaskedNearest(float max_sq_distance, const uint8_t* allowed) : worst_(max_sq_distance), allowed_(allowed) {}
  bool full() const { return found_; }
  float worstDist() const { return worst_; }
  bool addPoint(float sq_distance, uint32_t index) {
    if (allowed_ != nullptr && !allowed_[index]) return true;
    if (sq_distance <= worst_) {
      worst_ = sq_distance;
      index_ = index;
      found_ = true;
    }
    return true;
  }
  bool found() const { return found_; }
  uint32_t index() const { return index_; }

 private:
  float worst_;
  const uint8_t* allowed_;
  uint32_t index_ = 0;
  bool found_ = false;
};

}  // namespace

PointTree::PointTree(const std::vector<Eigen::Vector3f>& points) : adaptor_{points} {
  // Leaves of 16 points: small_gicp's and PCL's FLANN defaults are of that order; larger leaves
  // make the many one-neighbour searches of GICP slower.
  index_ = std::make_unique<Index>(
      3, adaptor_, nanoflann::KDTreeSingleIndexAdaptorParams(16, nanoflann::KDTreeSingleIndexAdaptorFlags::SkipInitialBuildIndex));
  if (!points.empty()) index_->buildIndex();
}

std::size_t PointTree::nearest_k(const Eigen::Vector3f& query, std::size_t k, uint32_t* indices,
                                 float* sq_distances) const {
  if (adaptor_.points.empty() || k == 0) return 0;
  return index_->knnSearch(query.data(), k, indices, sq_distances);
}

bool PointTree::nearest(const Eigen::Vector3f& query, float max_sq_distance, const uint8_t* allowed,
                        uint32_t& index, float& sq_distance) const {
  if (adaptor_.points.empty()) return false;
  MaskedNearest result(max_sq_distance, allowed);
  index_->findNeighbors(result, query.data(), nanoflann::SearchParams());
  if (!result.found()) return false;
  index = result.index();
  sq_distance = result.worstDist();
  return true;
}

}  // namespace bathyslam
