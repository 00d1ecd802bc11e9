#include "core/filter/voxel_filter.h"

#include <pcl/filters/voxel_grid.h>

namespace bathyslam {

Cloud::Ptr voxel_filter(const std::vector<Eigen::Vector3f>& points, const VoxelConfig& config) {
  auto raw = std::make_shared<Cloud>();
  raw->reserve(points.size());
  for (const Eigen::Vector3f& p : points) raw->emplace_back(p.x(), p.y(), p.z());
  auto filtered = std::make_shared<Cloud>();
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(raw);
  grid.setLeafSize(config.leaf_x_m, config.leaf_y_m, config.leaf_z_m);
  grid.filter(*filtered);
  return filtered;
}

}  // namespace bathyslam
