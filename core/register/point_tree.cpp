#include "core/register/point_tree.h"

namespace bathyslam {
namespace {

// nanoflann result set for the two nearest points that skips masked points and starts with the
// search bound as its worst distance, so the search prunes everything beyond it.
class MaskedTwoNearest {
 public:
  MaskedTwoNearest(float max_sq_distance, const uint8_t* allowed)
      : best_(max_sq_distance), second_(max_sq_distance), allowed_(allowed) {}
  bool full() const { return found_; }
  float worstDist() const { return second_; }
  bool addPoint(float sq_distance, uint32_t index) {
    if (allowed_ != nullptr && !allowed_[index]) return true;
    if (sq_distance <= best_) {
      if (found_) {
        second_ = best_;
        second_index_ = index_;
        found_second_ = true;
      }
      best_ = sq_distance;
      index_ = index;
      found_ = true;
    } else if (sq_distance < second_) {
      second_ = sq_distance;
      second_index_ = index;
      found_second_ = true;
    }
    return true;
  }
  PointTree::TwoNearest result() const { return {found_, index_, best_, found_second_, second_index_, second_}; }

 private:
  float best_, second_;
  const uint8_t* allowed_;
  uint32_t index_ = 0, second_index_ = 0;
  bool found_ = false, found_second_ = false;
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

PointTree::TwoNearest PointTree::nearest_two(const Eigen::Vector3f& query, float max_sq_distance,
                                            const uint8_t* allowed) const {
  if (adaptor_.points.empty()) return {false, 0, 0, false, 0, max_sq_distance};
  MaskedTwoNearest result(max_sq_distance, allowed);
  index_->findNeighbors(result, query.data(), nanoflann::SearchParams());
  return result.result();
}

}  // namespace bathyslam
