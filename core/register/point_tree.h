#pragma once
// register (own GICP): a KD-tree over a submap's points (nanoflann), built once per submap and
// shared by every pair the submap takes part in. Float points: a submap sits in its own frame,
// within a few hundred metres of its origin, where float keeps millimetres.
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <nanoflann.hpp>

namespace bathyslam {

class PointTree {
 public:
  // Keeps a reference to `points`: they must outlive the tree and not move.
  explicit PointTree(const std::vector<Eigen::Vector3f>& points);
  PointTree(const PointTree&) = delete;  // the index refers to adaptor_
  PointTree& operator=(const PointTree&) = delete;

  // The k nearest points (fewer if the cloud is smaller), nearest first; returns how many.
  std::size_t nearest_k(const Eigen::Vector3f& query, std::size_t k, uint32_t* indices, float* sq_distances) const;

  // The nearest and second-nearest points with `allowed[index]` set (all points if `allowed` is
  // null) within sqrt(max_sq_distance). The second's distance is what proves the nearest
  // unchanged after a small move (Associator, gicp_factor.h). The mask is how a pair registers
  // only its predicted overlap on a tree of the whole submap.
  struct TwoNearest {
    bool found = false;
    uint32_t index = 0;     // the nearest, if found
    float sq_distance = 0;  // to it
    bool found_second = false;
    uint32_t second_index = 0;
    float second_sq_distance = 0;  // to the second nearest; max_sq_distance if there is none
  };
  TwoNearest nearest_two(const Eigen::Vector3f& query, float max_sq_distance, const uint8_t* allowed) const;

 private:
  struct Adaptor {
    const std::vector<Eigen::Vector3f>& points;
    std::size_t kdtree_get_point_count() const { return points.size(); }
    float kdtree_get_pt(std::size_t i, std::size_t dim) const { return points[i][static_cast<int>(dim)]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const { return false; }
  };
  using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Adaptor>, Adaptor, 3, uint32_t>;

  Adaptor adaptor_;
  std::unique_ptr<Index> index_;
};

}  // namespace bathyslam
