#include "core/tiles/tile_files.h"

#include <atomic>
#include <optional>
#include <system_error>

#include "core/parallel/parallel_for.h"
#include "core/tiles/geotiff_writer.h"
#include "core/tiles/vdb_writer.h"

namespace bathyslam {

std::filesystem::path tile_stem(const TileId& id) {
  return std::filesystem::path(std::to_string(id.level)) / (std::to_string(id.col) + "_" + std::to_string(id.row));
}

TileFileCount write_tile_files(const GridRaster& level0, std::string_view crs, const std::filesystem::path& dir,
                               int threads) {
  TileFileCount written;
  for_each_level(level0, [&](int level, const GridRaster& raster, const std::vector<TileId>& ids) {
    const std::filesystem::path level_dir = dir / std::to_string(level);
    std::error_code ec;
    std::filesystem::create_directories(level_dir, ec);
    if (ec) throw std::runtime_error(level_dir.string() + ": cannot create folder: " + ec.message());
    // Tiles are independent files: cut and encode them in parallel.
    std::atomic<std::size_t> tiles = 0;
    parallel_for(ids.size(), threads, nullptr, [&](std::size_t k) {
      const std::optional<GridRaster> tile = cut_tile(raster, ids[k], level0.geometry.resolution_m);
      if (!tile) return;
      const std::string stem = (dir / tile_stem(ids[k])).string();
      write_geotiff(*tile, crs, stem + ".tif");
      write_vdb(*tile, crs, stem + ".vdb");
      ++tiles;
    });
    written.tiles += tiles;
    if (tiles > 0) written.levels = level + 1;
  });
  return written;
}

}  // namespace bathyslam
