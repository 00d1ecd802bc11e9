#pragma once
// Simulated lakebed: flat regions and undulating regions (mounds, ridges, channels, fine
// roughness) that alternate across the survey area, sampled on a fine grid.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace bathyslam::sim {

struct TerrainConfig {
  uint64_t seed = 1;
  double mean_depth_m = 10.0;
  double cell_m = 0.2;            // grid resolution of the sampled surface
  double region_size_m = 90.0;    // flat and rough regions alternate at about this scale
  double regional_relief_m = 1.0; // very gentle large-scale relief everywhere (lakebed slope)
  double flat_roughness_m = 0.01; // sediment texture of the flat lakebed
  // Rough regions: features per square metre and their sizes.
  double mound_density = 1.0 / 250.0;
  double ridge_density = 1.0 / 1500.0;
  double channel_density = 1.0 / 2500.0;
  double fine_roughness_m = 0.15;
  bool flat_only = false;         // a perfectly flat bottom at mean depth (sonar geometry tests)
};

// Axis-aligned area in the local map frame (metres east, north).
struct Area {
  Eigen::Vector2d min{0, 0};
  Eigen::Vector2d max{0, 0};
};

class Terrain {
 public:
  // Samples the terrain over `area` (and a little beyond, so rays near the edge still land).
  static Terrain generate(const TerrainConfig& config, const Area& area);

  // Elevation (metres, negative below the datum) at a map-frame position, bilinear between
  // grid samples; clamps outside the sampled area.
  double elevation(double x, double y) const;
  // How rough the terrain is at (x, y): 0 on the flat lakebed, 1 in undulating regions.
  double roughness_weight(double x, double y) const;
  // Largest surface slope (rise over run) anywhere; ray marching uses it as a safe step bound.
  double max_slope() const { return max_slope_; }
  const Area& area() const { return area_; }

 private:
  double sample(const std::vector<float>& grid, double x, double y) const;

  Area area_;
  double cell_m_ = 0.2;
  int cols_ = 0;
  int rows_ = 0;
  std::vector<float> elevation_;
  std::vector<float> roughness_;
  double max_slope_ = 1.0;
};

}  // namespace bathyslam::sim
