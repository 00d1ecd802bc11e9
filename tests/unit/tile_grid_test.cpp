#include "core/tiles/tile_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "core/fuse/fuse.h"

namespace bathyslam {
namespace {

TEST(TileGrid, TilesSitOnMultiplesOfTheirSizeFromTheCrsOrigin) {
  const GridGeometry g = tile_geometry({0, 1765, 18085}, 0.5);
  EXPECT_EQ(g.width, 512);
  EXPECT_EQ(g.height, 512);
  EXPECT_DOUBLE_EQ(g.west_m(), 1765 * 256.0);
  EXPECT_DOUBLE_EQ(g.south_m(), 18085 * 256.0);
  EXPECT_DOUBLE_EQ(g.north_m(), 18086 * 256.0);
  const GridGeometry up = tile_geometry({2, 441, 4521}, 0.5);
  EXPECT_DOUBLE_EQ(up.resolution_m, 2.0);
  EXPECT_DOUBLE_EQ(up.west_m(), 441 * 1024.0);
  // Negative coordinates floor: the tile west of the CRS origin is column -1.
  GridGeometry west_of_origin{0.5, -3, 10, 6, 2};
  const std::vector<TileId> ids = tiles_overlapping(west_of_origin, 0);
  ASSERT_EQ(ids.size(), 2u);
  EXPECT_EQ(ids[0], (TileId{0, -1, 0}));
  EXPECT_EQ(ids[1], (TileId{0, 0, 0}));
}

TEST(TileGrid, CoarseningEqualsFusingAtTwiceTheCellSize) {
  // The same soundings fused at 1 m and coarsened, and fused at 2 m directly.
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-7, 9);
  std::normal_distribution<float> z(-10, 0.3f);
  std::vector<Eigen::Vector3f> points;
  for (int k = 0; k < 3000; ++k) points.emplace_back(u(rng), u(rng), z(rng));
  const LocalOrigin origin{1000, 2001};  // odd metres: the 2 m lattice is not the 1 m grid's first cell
  GridFuser fine(origin, {1.0, 1}), coarse(origin, {2.0, 1});
  fine.add(points, Eigen::Isometry3d::Identity());
  coarse.add(points, Eigen::Isometry3d::Identity());
  const GridRaster coarsened = coarsen(fine.raster()), direct = coarse.raster();
  ASSERT_EQ(coarsened.geometry, direct.geometry);
  for (std::size_t i = 0; i < direct.geometry.cells(); ++i) {
    ASSERT_EQ(coarsened.valid(i), direct.valid(i)) << i;
    if (!direct.valid(i)) continue;
    EXPECT_EQ(coarsened.count[i], direct.count[i]);
    EXPECT_NEAR(coarsened.elevation[i], direct.elevation[i], 1e-4);
    EXPECT_NEAR(coarsened.uncertainty[i], direct.uncertainty[i], 1e-4);
  }
}

TEST(TileGrid, PyramidKeepsEverySoundingOnEachLevelAndEndsInOneTile) {
  // A 700 m × 300 m map at 0.5 m around UTM coordinates: several level-0 tiles.
  std::vector<Eigen::Vector3f> points;
  for (float x = 0; x < 700; x += 0.5f) {
    for (float y = 0; y < 300; y += 0.5f) points.emplace_back(x + 0.25f, y + 0.25f, -10);
  }
  GridFuser fuser({452000, 4630000}, {0.5, 1});
  fuser.add(points, Eigen::Isometry3d::Identity());
  const GridRaster level0 = fuser.raster();
  std::map<int, double> soundings_per_level;
  std::map<int, int> tiles_per_level;
  for_each_tile(level0, [&](const TileId& id, const GridRaster& tile) {
    EXPECT_EQ(tile.geometry, tile_geometry(id, 0.5));
    for (std::size_t i = 0; i < tile.geometry.cells(); ++i) {
      if (tile.valid(i)) soundings_per_level[id.level] += tile.count[i];
    }
    ++tiles_per_level[id.level];
  });
  ASSERT_FALSE(tiles_per_level.empty());
  EXPECT_GT(tiles_per_level[0], 4);
  EXPECT_EQ(tiles_per_level.rbegin()->second, 1) << "the last level is one tile";
  for (const auto& [level, soundings] : soundings_per_level) {
    EXPECT_EQ(soundings, static_cast<double>(points.size())) << "level " << level;
  }
}

}  // namespace
}  // namespace bathyslam
