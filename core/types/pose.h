#pragma once
// Navigation samples as rigid poses in the map frame (east, north, up; docs/design.md).
#include <Eigen/Geometry>

#include "core/types/survey.h"

namespace bathyslam {

// Where the map frame's origin sits in the projected CRS. Subtracting it keeps coordinates
// small enough for float clouds and PCL (metres east, north, up).
struct LocalOrigin {
  double easting = 0;
  double northing = 0;
};

// Rotation taking vectors of the vehicle frame (x forward, y starboard, z down) to the map frame
// (x east, y north, z up), from roll, pitch and heading (Z-Y-X Euler angles about NED).
Eigen::Matrix3d vehicle_to_map_rotation(double roll_deg, double pitch_deg, double heading_deg);

// Rotation taking vehicle-frame vectors to the level frame that keeps the vehicle's heading (x
// forward horizontal, z down the vertical), from roll and pitch: where sonar formats (GSF, EM
// .all) store beams, attitude already applied.
Eigen::Matrix3d vehicle_to_level_rotation(double roll_deg, double pitch_deg);

// The pose of the vehicle in the map frame: a point b in the vehicle frame lands at pose * b.
Eigen::Isometry3d vehicle_pose(const NavSample& nav, const LocalOrigin& origin);

// Inverse of vehicle_pose: the navigation sample (time left 0) that a pose corresponds to.
NavSample nav_from_pose(const Eigen::Isometry3d& pose, const LocalOrigin& origin);

}  // namespace bathyslam
