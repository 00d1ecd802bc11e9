#pragma once
// The fixed tile grid (docs/design.md pipeline: tiles). Tiles are 512 × 512 cells on the CRS-anchored
// lattice of core/fuse/grid.h: tile (level, col, row) holds global cells
// [col·512, col·512 + 511] × [row·512, row·512 + 511] of level `level`, whose cells are 2^level
// times the level-0 resolution. Rows count northward from the CRS origin (as in TMS), so a tile's
// south-west corner is (col, row) · 512 · resolution · 2^level and the same tile name means the
// same place in every survey of the same CRS and resolution; the four tiles (2c..2c+1, 2r..2r+1)
// of a level are exactly tile (c, r) of the next.
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "core/fuse/grid.h"

namespace bathyslam {

inline constexpr int kTileCells = 512;

struct TileId {
  int level = 0;
  std::int64_t col = 0, row = 0;
  bool operator==(const TileId&) const = default;
};

// The geometry of a tile whose level-0 cells are `level0_resolution_m`.
GridGeometry tile_geometry(const TileId& id, double level0_resolution_m);

// The tiles of `level` that overlap `geometry` (a raster of that level), west to east, south to north.
std::vector<TileId> tiles_overlapping(const GridGeometry& geometry, int level);

// The next level: each cell is the 2 × 2 cells of `fine` that it covers, pooled over the valid
// ones as if their soundings had been fused together (count summed, mean weighted by count,
// standard deviation of the pooled soundings); NaN where none is valid.
GridRaster coarsen(const GridRaster& fine);

// Visits the pyramid's levels, from `level0` up to the first level that fits in one tile, each
// with the tiles that overlap it. Only one level is in memory besides `level0`.
void for_each_level(const GridRaster& level0,
                    const std::function<void(int level, const GridRaster& raster, const std::vector<TileId>& tiles)>& visit);

// The tile `id` cut from its level's raster; nothing when it holds no valid cell.
std::optional<GridRaster> cut_tile(const GridRaster& level, const TileId& id, double level0_resolution_m);

// Visits every tile holding at least one valid cell, level by level (for_each_level), one tile at a time.
void for_each_tile(const GridRaster& level0, const std::function<void(const TileId&, const GridRaster&)>& visit);

}  // namespace bathyslam
