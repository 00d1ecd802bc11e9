#include "core/tiles/tile_grid.h"

#include <cmath>

namespace bathyslam {

GridGeometry tile_geometry(const TileId& id, double level0_resolution_m) {
  GridGeometry g;
  g.resolution_m = std::ldexp(level0_resolution_m, id.level);
  g.left = id.col * kTileCells;
  g.top = id.row * kTileCells + kTileCells - 1;
  g.width = g.height = kTileCells;
  return g;
}

std::vector<TileId> tiles_overlapping(const GridGeometry& geometry, int level) {
  std::vector<TileId> ids;
  if (geometry.cells() == 0) return ids;
  for (std::int64_t row = floor_div(geometry.bottom(), kTileCells); row <= floor_div(geometry.top, kTileCells); ++row) {
    for (std::int64_t col = floor_div(geometry.left, kTileCells); col <= floor_div(geometry.right(), kTileCells); ++col) {
      ids.push_back({level, col, row});
    }
  }
  return ids;
}

GridRaster coarsen(const GridRaster& fine) {
  const GridGeometry& f = fine.geometry;
  GridGeometry g;
  g.resolution_m = 2 * f.resolution_m;
  if (f.cells() == 0) return GridRaster::no_data(g);
  g.left = floor_div(f.left, 2);
  g.top = floor_div(f.top, 2);
  g.width = static_cast<int>(floor_div(f.right(), 2) - g.left + 1);
  g.height = static_cast<int>(g.top - floor_div(f.bottom(), 2) + 1);
  GridRaster out = GridRaster::no_data(g);
  std::size_t parts[4];
  for (std::int64_t row = g.bottom(); row <= g.top; ++row) {
    for (std::int64_t col = g.left; col <= g.right(); ++col) {
      int k = 0;
      double n = 0, weighted_sum = 0;
      for (std::int64_t fr = 2 * row; fr <= 2 * row + 1; ++fr) {
        for (std::int64_t fc = 2 * col; fc <= 2 * col + 1; ++fc) {
          if (!f.contains(fc, fr)) continue;
          const std::size_t i = f.index(fc, fr);
          if (!fine.valid(i)) continue;
          parts[k++] = i;
          n += fine.count[i];
          weighted_sum += static_cast<double>(fine.count[i]) * fine.elevation[i];
        }
      }
      if (k == 0) continue;
      const double mean = weighted_sum / n;
      // Pooled sum of squared deviations: each part's own plus its mean's offset from the pooled mean.
      double m2 = 0;
      for (int p = 0; p < k; ++p) {
        const std::size_t i = parts[p];
        const double s = fine.uncertainty[i], d = fine.elevation[i] - mean;
        if (!std::isnan(s)) m2 += (fine.count[i] - 1.0) * s * s;
        m2 += fine.count[i] * d * d;
      }
      const std::size_t o = g.index(col, row);
      out.elevation[o] = static_cast<float>(mean);
      out.uncertainty[o] = n > 1 ? static_cast<float>(std::sqrt(m2 / (n - 1))) : NAN;
      out.count[o] = static_cast<float>(n);
    }
  }
  return out;
}

void for_each_level(const GridRaster& level0,
                    const std::function<void(int level, const GridRaster& raster, const std::vector<TileId>& tiles)>& visit) {
  if (level0.valid_cells() == 0) return;
  const GridRaster* level = &level0;
  GridRaster coarser;
  for (int l = 0;; ++l) {
    const std::vector<TileId> ids = tiles_overlapping(level->geometry, l);
    visit(l, *level, ids);
    if (ids.size() <= 1) return;
    coarser = coarsen(*level);
    level = &coarser;
  }
}

std::optional<GridRaster> cut_tile(const GridRaster& level, const TileId& id, double level0_resolution_m) {
  GridRaster tile = crop(level, tile_geometry(id, level0_resolution_m));
  if (tile.valid_cells() == 0) return std::nullopt;
  return tile;
}

void for_each_tile(const GridRaster& level0, const std::function<void(const TileId&, const GridRaster&)>& visit) {
  for_each_level(level0, [&](int, const GridRaster& level, const std::vector<TileId>& ids) {
    for (const TileId& id : ids) {
      if (const std::optional<GridRaster> tile = cut_tile(level, id, level0.geometry.resolution_m)) visit(id, *tile);
    }
  });
}

}  // namespace bathyslam
