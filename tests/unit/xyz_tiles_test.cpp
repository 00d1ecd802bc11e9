// The map as XYZ tiles (core/tiles/xyz_tiles.h): where a tile lies, and what its pixels say
// about the COG it is drawn from.
#include "core/tiles/xyz_tiles.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <unistd.h>

#include <opencv2/imgcodecs.hpp>

#include "core/io/crs.h"
#include "core/tiles/geotiff_writer.h"
#include "core/tiles/relief_colours.h"

namespace bathyslam {
namespace {

constexpr double kWorld = 20037508.342789244;  // half of EPSG:3857's world, metres

TEST(XyzTiles, TileBoundsFollowTheXyzScheme) {
  const auto z0 = xyz_tile_bounds(0, 0, 0);
  EXPECT_NEAR(z0[0], -kWorld, 1e-6);
  EXPECT_NEAR(z0[3], kWorld, 1e-6);
  const auto ne = xyz_tile_bounds(1, 1, 0);  // y counts from the north
  EXPECT_NEAR(ne[0], 0, 1e-6);
  EXPECT_NEAR(ne[1], 0, 1e-6);
  EXPECT_NEAR(ne[2], kWorld, 1e-6);
  const auto [lon, lat] = mercator_to_lon_lat(kWorld, kWorld);
  EXPECT_NEAR(lon, 180, 1e-9);
  EXPECT_NEAR(lat, 85.0511287798, 1e-8);
  EXPECT_THROW(xyz_tile_bounds(25, 0, 0), std::invalid_argument);
  EXPECT_THROW(xyz_tile_bounds(1, 2, 0), std::invalid_argument);
  EXPECT_THROW(xyz_tile_bounds(3, 0, -1), std::invalid_argument);
}

// The XYZ tile and pixel of a longitude/latitude at zoom z.
struct TilePixel {
  int x, y, i, j;
};
TilePixel tile_pixel(double lon, double lat, int z) {
  const double n = std::ldexp(1.0, z), phi = lat * M_PI / 180;
  const double fx = (lon + 180) / 360 * n, fy = (1 - std::log(std::tan(phi) + 1 / std::cos(phi)) / M_PI) / 2 * n;
  return {static_cast<int>(fx), static_cast<int>(fy), static_cast<int>((fx - std::floor(fx)) * 256),
          static_cast<int>((fy - std::floor(fy)) * 256)};
}

class XyzTileSourceTest : public ::testing::Test {
 protected:
  // 300 x 200 cells at 0.5 m in UTM 51N, deepening 2 cm a cell to the east; no data in the
  // westernmost 40 columns.
  void SetUp() override {
    GridRaster map = GridRaster::no_data(GridGeometry{0.5, 1'000'000, 7'000'000, 300, 200});
    for (int y = 0; y < 200; ++y) {
      for (int x = 40; x < 300; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * 300 + x;
        map.elevation[i] = static_cast<float>(-20 - 0.02 * x), map.uncertainty[i] = 0.01f, map.count[i] = 5;
      }
    }
    const auto path = std::filesystem::temp_directory_path() / ("xyz_test_" + std::to_string(::getpid()) + ".tif");
    write_geotiff(map, "EPSG:32651", path);
    std::ifstream in(path, std::ios::binary);
    source_ = std::make_unique<XyzTileSource>(std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {}), "EPSG:32651");
    std::filesystem::remove(path);
  }
  // The elevation the unshaded tile's colour at (lon, lat) stands for; nullopt where transparent.
  std::optional<double> elevation_at(double easting, double northing, int z) {
    const auto p = GeographicProjection("EPSG:32651").inverse(easting, northing);
    const TilePixel t = tile_pixel(p.longitude_deg, p.latitude_deg, z);
    const auto png = source_->tile_png(z, t.x, t.y, false);
    EXPECT_TRUE(png.has_value());
    const cv::Mat image = cv::imdecode(*png, cv::IMREAD_UNCHANGED);
    const cv::Vec4b pixel = image.at<cv::Vec4b>(t.j, t.i);
    if (pixel[3] == 0) return std::nullopt;
    const Ramp ramp = turbo_ramp();
    int best = 0;
    for (int k = 1; k < 256; ++k) {
      if (cv::norm(cv::Vec3d(ramp[k]) - cv::Vec3d(pixel[0], pixel[1], pixel[2])) <
          cv::norm(cv::Vec3d(ramp[best]) - cv::Vec3d(pixel[0], pixel[1], pixel[2])))
        best = k;
    }
    const auto [lo, hi] = source_->ramp_range();
    return lo + (hi - lo) * best / 255;
  }
  std::unique_ptr<XyzTileSource> source_;
};

TEST_F(XyzTileSourceTest, APixelsColourIsTheElevationOfTheCellUnderIt) {
  const auto [lo, hi] = source_->ramp_range();
  EXPECT_NEAR(lo, -20 - 0.02 * 297, 0.05);  // the 1 % quantile: deep, in the east
  EXPECT_NEAR(hi, -20 - 0.02 * 42, 0.05);
  for (const int col : {60, 150, 280}) {
    const double easting = (1'000'000 + col + 0.5) * 0.5, northing = (7'000'000 - 100 + 0.5) * 0.5;
    const auto z = elevation_at(easting, northing, 21);  // 7.5 cm pixels: well inside the cell
    ASSERT_TRUE(z.has_value()) << col;
    EXPECT_NEAR(*z, -20 - 0.02 * col, std::abs(hi - lo) / 255 + 1e-6) << col;
  }
  EXPECT_FALSE(elevation_at((1'000'000 + 20.5) * 0.5, (7'000'000 - 100.5) * 0.5, 21).has_value()) << "no data: transparent";
}

TEST_F(XyzTileSourceTest, TilesAwayFromTheMapAreNoneAndShadingChangesTheColours) {
  EXPECT_FALSE(source_->tile_png(19, 0, 0, true).has_value());
  const auto [west, south, east, north] = source_->lon_lat_bounds();
  EXPECT_GT(east, west);
  EXPECT_GT(north, south);
  const TilePixel t = tile_pixel((west + east) / 2, (south + north) / 2, 18);
  const auto shaded = source_->tile_png(18, t.x, t.y, true), flat = source_->tile_png(18, t.x, t.y, false);
  ASSERT_TRUE(shaded && flat);
  EXPECT_NE(*shaded, *flat);
  const auto world = source_->tile_png(0, 0, 0, true);  // the whole world: the map is a few pixels
  ASSERT_TRUE(world.has_value());
  EXPECT_EQ(cv::imdecode(*world, cv::IMREAD_UNCHANGED).type(), CV_8UC4);
}

}  // namespace
}  // namespace bathyslam
