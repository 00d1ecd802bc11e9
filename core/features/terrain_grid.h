#pragma once
// features (gridding): a submap's soundings as a 2.5D terrain surface on a regular grid in the
// submap frame, by inverse distance weighting, with a mask of the cells that have data.
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace bathyslam {

struct GridConfig {
  double cell_m = 0.5;            // grid resolution: 11 cells span 5.5 m, a patch that fits an overlap
  double idw_radius_cells = 1.0;  // soundings within this many cells of a cell centre contribute
  double idw_power = 2.0;
  template <typename Field>
  void fields(Field&& field) {
    field("cell_m", cell_m, 0.05, 1e5);
    field("idw_radius_cells", idw_radius_cells, 0.5, 10);
    field("idw_power", idw_power, 0, 10);
  }
};

struct TerrainGrid {
  double cell_m = 1.0;
  Eigen::Vector2d origin{0, 0};  // submap-frame (x, y) of the centre of cell (row 0, col 0)
  cv::Mat elevation;             // CV_32F, metres up (the submap frame's z is down); 0 where invalid
  cv::Mat valid;                 // CV_8U, 1 where some sounding lies within the IDW radius

  int rows() const { return elevation.rows; }
  int cols() const { return elevation.cols; }
  // Submap-frame (x, y) of a cell position (col = x index, row = y index; fractional allowed).
  Eigen::Vector2d position(double col, double row) const { return origin + cell_m * Eigen::Vector2d(col, row); }
  int valid_cells() const { return cv::countNonZero(valid); }
};

// Grids soundings given in the submap frame (x forward, y starboard, z down).
TerrainGrid grid_terrain(const std::vector<Eigen::Vector3f>& points, const GridConfig& config = {});

}  // namespace bathyslam
