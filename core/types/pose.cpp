#include "core/types/pose.h"

#include <algorithm>
#include <cmath>

namespace bathyslam {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

// NED -> ENU swaps the horizontal axes and flips the vertical one.
Eigen::Matrix3d ned_to_enu() {
  Eigen::Matrix3d m;
  m << 0, 1, 0,
       1, 0, 0,
       0, 0, -1;
  return m;
}

}  // namespace

Eigen::Matrix3d vehicle_to_map_rotation(double roll_deg, double pitch_deg, double heading_deg) {
  const Eigen::Matrix3d body_to_ned =
      (Eigen::AngleAxisd(heading_deg * kDegToRad, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(pitch_deg * kDegToRad, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(roll_deg * kDegToRad, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  return ned_to_enu() * body_to_ned;
}

Eigen::Matrix3d vehicle_to_level_rotation(double roll_deg, double pitch_deg) {
  return (Eigen::AngleAxisd(pitch_deg * kDegToRad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll_deg * kDegToRad, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Isometry3d vehicle_pose(const NavSample& nav, const LocalOrigin& origin) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = vehicle_to_map_rotation(nav.roll_deg, nav.pitch_deg, nav.heading_deg);
  pose.translation() = Eigen::Vector3d(nav.easting - origin.easting,
                                       nav.northing - origin.northing, -nav.depth_m);
  return pose;
}

NavSample nav_from_pose(const Eigen::Isometry3d& pose, const LocalOrigin& origin) {
  const Eigen::Matrix3d body_to_ned = ned_to_enu().transpose() * pose.linear();
  // Z-Y-X Euler angles of body_to_ned; pitch stays within ±90° for a vehicle that swims.
  const double pitch = std::asin(std::clamp(-body_to_ned(2, 0), -1.0, 1.0));
  const double roll = std::atan2(body_to_ned(2, 1), body_to_ned(2, 2));
  double heading = std::atan2(body_to_ned(1, 0), body_to_ned(0, 0)) / kDegToRad;
  if (heading < 0) heading += 360.0;
  if (heading >= 360.0) heading -= 360.0;  // -0.0 + 360 rounds to 360
  NavSample nav;
  nav.easting = pose.translation().x() + origin.easting;
  nav.northing = pose.translation().y() + origin.northing;
  nav.depth_m = -pose.translation().z();
  nav.roll_deg = roll / kDegToRad;
  nav.pitch_deg = pitch / kDegToRad;
  nav.heading_deg = heading;
  return nav;
}

}  // namespace bathyslam
