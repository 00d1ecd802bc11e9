// The difference of two epochs: a known change on a sloping, noisy seabed, with the second
// surface shifted as a registration error would shift it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/fuse/difference.h"
#include "core/products/difference_products.h"

namespace bathyslam {
namespace {

// A 200 x 120 m seabed of 0.5 m cells: a slope, ridges, and sounding noise in each cell's mean.
GridRaster surface(std::int64_t left, std::int64_t top, double shift_x_m, double vertical_m, bool changed, unsigned seed) {
  GridGeometry g;
  g.resolution_m = 0.5;
  g.left = left;
  g.top = top;
  g.width = 400;
  g.height = 240;
  GridRaster r = GridRaster::no_data(g);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 0.01);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const double e = (g.left + x + 0.5) * g.resolution_m + shift_x_m, n = (g.top - y + 0.5) * g.resolution_m;
      double z = -10 + 0.05 * e + 0.8 * std::sin(e / 7.0) * std::cos(n / 11.0) + vertical_m;
      // A pit 0.5 m deep, 10 m across, and a 20 x 10 m area dredged by 0.3 m.
      if (changed && std::hypot(e - 60, n - 60) < 5) z -= 0.5;
      if (changed && std::abs(e - 140) < 10 && std::abs(n - 40) < 5) z -= 0.3;
      const std::size_t i = static_cast<std::size_t>(y) * g.width + x;
      r.elevation[i] = static_cast<float>(z + noise(rng));
      r.uncertainty[i] = 0.05f;
      r.count[i] = 25;
    }
  }
  return r;
}

TEST(Difference, FindsTheChangesAndTheirVolumesAndLittleElse) {
  const GridRaster before = surface(0, 239, 0, 0, false, 1);
  // The later survey a little off (10 cm east, 2 cm up) and one column of cells beyond the first.
  const GridRaster after = surface(1, 239, 0.10, 0.02, true, 2);
  const DifferenceMap d = difference_map(before, after);
  EXPECT_EQ(d.geometry.width, 399);
  EXPECT_EQ(d.cells_compared, 399u * 240u);
  // The registration's error shows: its 2 cm vertical offset is taken out as a local offset, and
  // what the shift leaves on the slopes widens the sigma, against the same surfaces registered.
  const DifferenceMap registered = difference_map(before, surface(1, 239, 0, 0, true, 2));
  EXPECT_NEAR(d.offset_rms_m, 0.02, 0.01);
  EXPECT_LT(registered.offset_rms_m, 0.005);
  EXPECT_GT(d.sigma_horizontal_m, registered.sigma_horizontal_m + 0.02);
  ASSERT_GE(d.areas.size(), 2u);
  const ChangedArea& dredged = d.areas[0];
  EXPECT_NEAR(dredged.area_m2, 200, 25);
  EXPECT_NEAR(dredged.lost_m3, 60, 8);
  EXPECT_NEAR(dredged.easting, 140, 1);
  EXPECT_NEAR(dredged.northing, 40, 1);
  const ChangedArea& pit = d.areas[1];
  EXPECT_NEAR(pit.area_m2, M_PI * 25, 12);
  EXPECT_NEAR(pit.largest_change_m, -0.5, 0.1);
  // Outside the changes, few cells flagged.
  std::size_t flagged_elsewhere = 0, elsewhere = 0;
  for (int y = 0; y < d.geometry.height; ++y) {
    for (int x = 0; x < d.geometry.width; ++x) {
      const double e = (d.geometry.left + x + 0.5) * 0.5, n = (d.geometry.top - y + 0.5) * 0.5;
      if (std::hypot(e - 60, n - 60) < 7 || (std::abs(e - 140) < 12 && std::abs(n - 40) < 7)) continue;
      ++elsewhere;
      flagged_elsewhere += d.significant[static_cast<std::size_t>(y) * d.geometry.width + x] == 1.0f;
    }
  }
  EXPECT_LT(static_cast<double>(flagged_elsewhere) / elsewhere, 0.01);
}

TEST(Difference, SurfacesThatDoNotMeetCompareNothing) {
  const DifferenceMap d = difference_map(surface(0, 239, 0, 0, false, 1), surface(1000, 239, 0, 0, false, 2));
  EXPECT_EQ(d.cells_compared, 0u);
  EXPECT_TRUE(d.areas.empty());
}

// Which epochs a site job compares: every pair of a few surveys, and beyond that each survey from
// the datum and from the one before (20 surveys: 37 maps, not 190).
TEST(Difference, ASiteComparesEveryPairOfAFewSurveysAndNeighboursBeyond) {
  EXPECT_TRUE(difference_pairs(1).empty());
  EXPECT_EQ(difference_pairs(3), (std::vector<std::pair<int, int>>{{0, 1}, {0, 2}, {1, 2}}));
  EXPECT_EQ(difference_pairs(kAllDifferencesUpTo).size(), 10u);
  const auto twenty = difference_pairs(20);
  EXPECT_EQ(twenty.size(), 19u + 18u);
  for (int k = 1; k < 20; ++k) {
    EXPECT_NE(std::find(twenty.begin(), twenty.end(), std::pair{0, k}), twenty.end()) << k;
    EXPECT_NE(std::find(twenty.begin(), twenty.end(), std::pair{k - 1, k}), twenty.end()) << k;
  }
}

}  // namespace
}  // namespace bathyslam
