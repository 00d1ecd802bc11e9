#pragma once
// The tile pyramid on disk: {dir}/{level}/{col}_{row}.tif (COG) and .vdb for every tile of
// core/tiles/tile_grid.h that holds data.
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

#include "core/fuse/grid.h"
#include "core/tiles/tile_grid.h"

namespace bathyslam {

// "{level}/{col}_{row}" (no extension), relative to the tile folder.
std::filesystem::path tile_stem(const TileId& id);

struct TileFileCount {
  std::size_t tiles = 0;  // each written as .tif and .vdb
  int levels = 0;
};

// Writes every tile of the pyramid over `level0` on `threads` threads; throws std::runtime_error
// naming the file that could not be written.
TileFileCount write_tile_files(const GridRaster& level0, std::string_view crs, const std::filesystem::path& dir,
                               int threads = 1);

}  // namespace bathyslam
