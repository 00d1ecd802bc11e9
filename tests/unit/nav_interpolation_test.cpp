#include "core/sync/nav_interpolation.h"

#include <gtest/gtest.h>

namespace bathyslam {
namespace {

TEST(InterpolateNav, PositionIsLinearInTime) {
  const std::vector<NavSample> nav = {{10.0, 100, 200, 5, 0, 0, 90}, {12.0, 104, 200, 7, 0, 0, 90}};
  const auto s = interpolate_nav(nav, 10.5);
  ASSERT_TRUE(s);
  EXPECT_DOUBLE_EQ(s->time, 10.5);
  EXPECT_NEAR(s->easting, 101.0, 1e-9);
  EXPECT_NEAR(s->depth_m, 5.5, 1e-9);
  EXPECT_NEAR(s->heading_deg, 90.0, 1e-9);
}

TEST(InterpolateNav, HeadingTakesTheShortWayThroughNorth) {
  const std::vector<NavSample> nav = {{0.0, 0, 0, 0, 0, 0, 350}, {1.0, 0, 0, 0, 0, 0, 10}};
  const auto s = interpolate_nav(nav, 0.25);
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->heading_deg, 355.0, 1e-9);
}

TEST(InterpolateNav, OutsideTheSpanGivesNothing) {
  const std::vector<NavSample> nav = {{10.0, 0, 0, 0, 0, 0, 0}, {11.0, 1, 0, 0, 0, 0, 0}};
  EXPECT_FALSE(interpolate_nav(nav, 9.999));
  EXPECT_FALSE(interpolate_nav(nav, 11.001));
  EXPECT_TRUE(interpolate_nav(nav, 11.0));
  EXPECT_TRUE(interpolate_nav(nav, 10.0));
}

}  // namespace
}  // namespace bathyslam
