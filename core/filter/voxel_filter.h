#pragma once
// filter: voxel downsampling of a submap (Table 1 (a): 0.2 x 0.2 x 0.1 m), as a PCL cloud ready
// for registration.
#include <vector>

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace bathyslam {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

struct VoxelConfig {
  float leaf_x_m = 0.2f;
  float leaf_y_m = 0.2f;
  float leaf_z_m = 0.1f;
  template <typename Field>
  void fields(Field&& field) {
    field("leaf_x_m", leaf_x_m, 0.01, 1e5);
    field("leaf_y_m", leaf_y_m, 0.01, 1e5);
    field("leaf_z_m", leaf_z_m, 0.01, 1e5);
  }
};

// Points must be centred (submap frame): PCL works in float.
Cloud::Ptr voxel_filter(const std::vector<Eigen::Vector3f>& points, const VoxelConfig& config = {});

}  // namespace bathyslam
