#pragma once
// register (own GICP): nearest-neighbour search over a submap's soundings, built once per submap
// and shared by every pair the submap takes part in. Soundings lie on a surface seen from above,
// so a 2-D grid of columns (x, y cells holding a few points each, stored column by column) finds
// a point's neighbours in the handful of columns around it, nearest columns first, and stops
// when no further column can hold anything closer. On `lake` it took 22-25 % off our GICP's
// CPU against nanoflann's KD-tree (docs/performance.md). The answers are exact in 3-D: a
// column ring is skipped only when its horizontal distance alone exceeds what was found; steep
// walls just make columns fuller. Float points: a submap sits in its own frame, within a few
// hundred metres of its origin, where float keeps millimetres.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace bathyslam {

class ColumnGrid {
 public:
  // Columns sized to hold `points_per_column` points on average over the points' bounding box.
  explicit ColumnGrid(const std::vector<Eigen::Vector3f>& points, double points_per_column = kPointsPerColumn);

  // The k nearest points with `allowed[index]` set (all points if `allowed` is null) closer
  // than sqrt(max_sq_distance), nearest first; returns how many. Indices are into the points
  // the grid was built from. The mask is how a pair registers only its predicted overlap on
  // the grid of the whole submap. A query that is not finite finds nothing.
  std::size_t nearest_within(const Eigen::Vector3f& query, std::size_t k, float max_sq_distance, const uint8_t* allowed,
                             uint32_t* indices, float* sq_distances) const;

  // Of each column holding any point, the point horizontally nearest its centre: a sample of
  // the points spread as evenly as the columns, denser areas thinned the most. `column_points`,
  // if given, receives how many points each one's column holds.
  std::vector<uint32_t> central_points(std::vector<uint32_t>* column_points = nullptr) const;

  float cell_m() const { return cell_m_; }
  std::size_t bytes() const;

  // About this many points per column: enough that a column is worth visiting, few enough that
  // the nearest few lie within one ring of columns.
  static constexpr double kPointsPerColumn = 3.0;

 private:
  Eigen::Vector2f origin_ = Eigen::Vector2f::Zero();  // the grid's lower x, y corner
  float cell_m_ = 1;
  int columns_x_ = 0, columns_y_ = 0;
  std::vector<uint32_t> first_;           // per column (row-major in y), where its points start; one more at the end
  std::vector<Eigen::Vector3f> sorted_;   // the points, column by column
  std::vector<uint32_t> index_;           // sorted_[s] is points[index_[s]]
};

}  // namespace bathyslam
