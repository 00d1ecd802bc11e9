#include "core/tiles/tile_files.h"

#include <algorithm>
#include <system_error>

#include "core/tiles/geotiff_writer.h"
#include "core/tiles/vdb_writer.h"

namespace bathyslam {

std::filesystem::path tile_stem(const TileId& id) {
  return std::filesystem::path(std::to_string(id.level)) / (std::to_string(id.col) + "_" + std::to_string(id.row));
}

TileFileCount write_tile_files(const GridRaster& level0, std::string_view crs, const std::filesystem::path& dir) {
  TileFileCount written;
  for_each_tile(level0, [&](const TileId& id, const GridRaster& tile) {
    const std::filesystem::path stem = dir / tile_stem(id);
    std::error_code ec;
    std::filesystem::create_directories(stem.parent_path(), ec);
    if (ec) throw std::runtime_error(stem.parent_path().string() + ": cannot create folder: " + ec.message());
    write_geotiff(tile, crs, stem.string() + ".tif");
    write_vdb(tile, crs, stem.string() + ".vdb");
    ++written.tiles;
    written.levels = std::max(written.levels, id.level + 1);
  });
  return written;
}

}  // namespace bathyslam
