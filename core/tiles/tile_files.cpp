#include "core/tiles/tile_files.h"

#include <exception>
#include <optional>
#include <system_error>

#include "core/tiles/geotiff_writer.h"
#include "core/tiles/vdb_writer.h"

namespace bathyslam {

std::filesystem::path tile_stem(const TileId& id) {
  return std::filesystem::path(std::to_string(id.level)) / (std::to_string(id.col) + "_" + std::to_string(id.row));
}

TileFileCount write_tile_files(const GridRaster& level0, std::string_view crs, const std::filesystem::path& dir) {
  TileFileCount written;
  for_each_level(level0, [&](int level, const GridRaster& raster, const std::vector<TileId>& ids) {
    const std::filesystem::path level_dir = dir / std::to_string(level);
    std::error_code ec;
    std::filesystem::create_directories(level_dir, ec);
    if (ec) throw std::runtime_error(level_dir.string() + ": cannot create folder: " + ec.message());
    // Tiles are independent files: cut and encode them on all cores. An exception must not leave
    // an OpenMP region, so the first one is kept and rethrown after it.
    std::exception_ptr failure;
    std::size_t tiles = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : tiles)
    for (std::size_t k = 0; k < ids.size(); ++k) {
      try {
        const std::optional<GridRaster> tile = cut_tile(raster, ids[k], level0.geometry.resolution_m);
        if (!tile) continue;
        const std::string stem = (dir / tile_stem(ids[k])).string();
        write_geotiff(*tile, crs, stem + ".tif");
        write_vdb(*tile, crs, stem + ".vdb");
        ++tiles;
      } catch (...) {
#pragma omp critical(bathyslam_tile_failure)
        if (!failure) failure = std::current_exception();
      }
    }
    if (failure) std::rethrow_exception(failure);
    written.tiles += tiles;
    if (tiles > 0) written.levels = level + 1;
  });
  return written;
}

}  // namespace bathyslam
