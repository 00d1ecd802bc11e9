#pragma once
// A multibeam echosounder: a fan of beams across track, each intersected with the terrain.
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "core/sim/terrain.h"
#include "core/types/survey.h"

namespace bathyslam::sim {

struct SonarConfig {
  int beams = 512;
  double swath_deg = 140.0;
  double ping_rate_hz = 10.0;
  double noise_base_m = 0.05;          // range noise sigma = base + fraction * depth
  double noise_depth_fraction = 0.002;
  double max_range_m = 200.0;
};

// Angle of beam `index` from nadir, positive to starboard (radians).
double beam_angle_rad(const SonarConfig& config, int index);

// The soundings of one ping, in the vehicle frame, from the vehicle's true pose in the map
// frame. Beams that find no bottom within range return nothing.
std::vector<Beam> ping(const Terrain& terrain, const Eigen::Isometry3d& true_pose,
                       const SonarConfig& config, std::mt19937_64& rng);

}  // namespace bathyslam::sim
