#include "core/features/terrain_grid.h"

#include <cmath>

namespace bathyslam {

TerrainGrid grid_terrain(const std::vector<Eigen::Vector3f>& points, const GridConfig& config) {
  TerrainGrid grid;
  grid.cell_m = config.cell_m;
  if (points.empty()) {
    grid.elevation = cv::Mat::zeros(0, 0, CV_32F);
    grid.valid = cv::Mat::zeros(0, 0, CV_8U);
    return grid;
  }
  Eigen::Vector2f lo = points.front().head<2>(), hi = lo;
  for (const Eigen::Vector3f& p : points) {
    lo = lo.cwiseMin(p.head<2>());
    hi = hi.cwiseMax(p.head<2>());
  }
  const double cell = config.cell_m;
  grid.origin = (lo.cast<double>().array() / cell).floor().matrix() * cell + Eigen::Vector2d::Constant(cell / 2);
  const int cols = static_cast<int>(std::floor((hi.x() - grid.origin.x()) / cell + 0.5)) + 1;
  const int rows = static_cast<int>(std::floor((hi.y() - grid.origin.y()) / cell + 0.5)) + 1;

  cv::Mat weighted = cv::Mat::zeros(rows, cols, CV_64F), weights = cv::Mat::zeros(rows, cols, CV_64F);
  // Distances squared and in cells (a constant factor cancels in the weighted mean): the weight
  // d^-power is (d^2)^(-power/2), so the default power of 2 needs neither a root nor pow.
  const double radius_sq = config.idw_radius_cells * config.idw_radius_cells;
  const double floor_sq = 0.05 * 0.05;  // keeps a sounding on a cell centre from taking all the weight
  auto weight = [&](double d_sq) {
    d_sq = std::max(d_sq, floor_sq);
    return config.idw_power == 2.0 ? 1.0 / d_sq : std::pow(d_sq, -config.idw_power / 2);
  };
  const int reach = static_cast<int>(std::ceil(config.idw_radius_cells));
  for (const Eigen::Vector3f& p : points) {
    const double fx = (p.x() - grid.origin.x()) / cell, fy = (p.y() - grid.origin.y()) / cell;
    const int c0 = static_cast<int>(std::lround(fx)), r0 = static_cast<int>(std::lround(fy));
    for (int r = std::max(0, r0 - reach); r <= std::min(rows - 1, r0 + reach); ++r) {
      for (int c = std::max(0, c0 - reach); c <= std::min(cols - 1, c0 + reach); ++c) {
        const double d_sq = (fx - c) * (fx - c) + (fy - r) * (fy - r);
        if (d_sq > radius_sq) continue;
        const double w = weight(d_sq);
        weighted.at<double>(r, c) += w * -p.z();
        weights.at<double>(r, c) += w;
      }
    }
  }
  grid.elevation = cv::Mat::zeros(rows, cols, CV_32F);
  grid.valid = cv::Mat::zeros(rows, cols, CV_8U);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      if (weights.at<double>(r, c) <= 0) continue;
      grid.elevation.at<float>(r, c) = static_cast<float>(weighted.at<double>(r, c) / weights.at<double>(r, c));
      grid.valid.at<uint8_t>(r, c) = 1;
    }
  }
  return grid;
}

}  // namespace bathyslam
