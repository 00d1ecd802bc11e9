#include "server/scheduler/map_products.h"

#include <charconv>
#include <fstream>

#include "core/tiles/bag_writer.h"
#include "core/tiles/geotiff_writer.h"
#include "core/tiles/quicklook.h"
#include "core/tiles/tile_files.h"
#include "core/tiles/tile_grid.h"
#include "server/scratch_dir.h"

namespace bathyslam::server {
namespace {

storage::Bytes file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  storage::Bytes bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.eof() && in.fail()) throw std::runtime_error(path.string() + ": cannot read");
  return bytes;
}

int epsg_of(const std::string& crs) {
  int code = 0;
  if (crs.rfind("EPSG:", 0) == 0) std::from_chars(crs.data() + 5, crs.data() + crs.size(), code);
  return code;
}

}  // namespace

MapProducts make_map_products(const PipelineResult& result, const SurveyMetadata& survey, const FuseConfig& fuse,
                              const std::filesystem::path& scratch) {
  MapProducts products;
  const GridRaster map = fuse_submaps(result.submaps, result.optimized_poses, fuse);
  if (map.valid_cells() == 0) return products;
  const ScratchDir scratch_dir(scratch, "map");
  const std::filesystem::path& dir = scratch_dir.path();

  write_geotiff(map, survey.crs, dir / "map.tif");
  products.tiles.push_back({{"cog", 0, 0, 0}, file_bytes(dir / "map.tif")});
  write_bag(map, survey.crs, map_bag_metadata(survey.name, to_string(result.config.configuration)), dir / "map.bag");
  products.tiles.push_back({{"bag", 0, 0, 0}, file_bytes(dir / "map.bag")});
  const TileFileCount count = write_tile_files(map, survey.crs, dir / "tiles");
  // The same pyramid as the files: every tile with data, a PNG quicklook next to its .tif/.vdb.
  for_each_tile(map, [&](const TileId& id, const GridRaster& tile) {
    const std::filesystem::path stem = dir / "tiles" / tile_stem(id);
    const int col = static_cast<int>(id.col), row = static_cast<int>(id.row);
    products.tiles.push_back({{"geotiff", id.level, col, row}, file_bytes(stem.string() + ".tif")});
    products.tiles.push_back({{"openvdb", id.level, col, row}, file_bytes(stem.string() + ".vdb")});
    products.tiles.push_back({{"png", id.level, col, row},
                              hillshade_png(tile, "level " + std::to_string(id.level) + ", tile " +
                                                      std::to_string(col) + " " + std::to_string(row))});
  });
  const GridGeometry& g = map.geometry;
  products.grid = {epsg_of(survey.crs), g.resolution_m, g.west_m(), g.south_m(), g.east_m(), g.north_m(), kTileCells,
                   count.levels};

  const std::string name = to_string(result.config.configuration);
  products.plots["map.png"] = hillshade_png(map, survey.name + " (" + name + ")");
  if (result.config.configuration != Configuration::kOdometry)
    products.plots["map_difference.png"] =
        difference_png(map, fuse_submaps(result.submaps, result.dr_poses, fuse), name + " minus dead reckoning, elevation");
  return products;
}

}  // namespace bathyslam::server
