#include "core/types/pose.h"

#include <gtest/gtest.h>

namespace bathyslam {
namespace {

TEST(VehiclePose, HeadingEastPointsForwardEastAndStarboardSouth) {
  const NavSample nav{0, 1000.0, 2000.0, 5.0, 0, 0, 90.0};
  const Eigen::Isometry3d pose = vehicle_pose(nav, LocalOrigin{990.0, 1990.0});
  EXPECT_TRUE(pose.translation().isApprox(Eigen::Vector3d(10, 10, -5)));
  EXPECT_TRUE((pose.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d(1, 0, 0), 1e-12));
  EXPECT_TRUE((pose.linear() * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d(0, -1, 0), 1e-12));
  EXPECT_TRUE((pose.linear() * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d(0, 0, -1), 1e-12));
}

TEST(VehiclePose, PositiveRollTiltsStarboardDown) {
  const NavSample nav{0, 0, 0, 0, 10.0, 0, 0};
  const Eigen::Vector3d starboard = vehicle_pose(nav, {}).linear() * Eigen::Vector3d::UnitY();
  EXPECT_LT(starboard.z(), 0);  // map z is up
  EXPECT_NEAR(starboard.z(), -std::sin(10.0 * M_PI / 180), 1e-12);
}

TEST(VehiclePose, NavFromPoseInvertsVehiclePose) {
  const LocalOrigin origin{452000, 4630000};
  for (double heading : {0.0, 45.0, 179.0, 181.0, 359.5}) {
    const NavSample nav{0, 452123.4, 4630456.7, 3.2, -2.5, 1.25, heading};
    const NavSample back = nav_from_pose(vehicle_pose(nav, origin), origin);
    EXPECT_NEAR(back.easting, nav.easting, 1e-9);
    EXPECT_NEAR(back.northing, nav.northing, 1e-9);
    EXPECT_NEAR(back.depth_m, nav.depth_m, 1e-12);
    EXPECT_NEAR(back.roll_deg, nav.roll_deg, 1e-9);
    EXPECT_NEAR(back.pitch_deg, nav.pitch_deg, 1e-9);
    EXPECT_NEAR(back.heading_deg, nav.heading_deg, 1e-9);
  }
}

}  // namespace
}  // namespace bathyslam
