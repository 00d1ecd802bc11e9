#include "server/scheduler/map_products.h"

#include <charconv>
#include <fstream>

#include "core/products/map_products.h"
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
  const ScratchDir scratch_dir(scratch, "map");
  const std::filesystem::path& dir = scratch_dir.path();
  const MapFiles files = write_map_products(result, survey, fuse, dir);
  if (!files.written) return products;

  products.tiles.push_back({{"cog", 0, 0, 0}, file_bytes(dir / "map.tif")});
  products.tiles.push_back({{"bag", 0, 0, 0}, file_bytes(dir / "map.bag")});
  for (const TileId& id : files.tile_ids) {
    const std::string stem = (dir / "tiles" / tile_stem(id)).string();
    const int col = static_cast<int>(id.col), row = static_cast<int>(id.row);
    products.tiles.push_back({{"geotiff", id.level, col, row}, file_bytes(stem + ".tif")});
    products.tiles.push_back({{"openvdb", id.level, col, row}, file_bytes(stem + ".vdb")});
    products.tiles.push_back({{"png", id.level, col, row}, file_bytes(stem + ".png")});
  }
  const GridGeometry& g = files.geometry;
  products.grid = {epsg_of(survey.crs), g.resolution_m, g.west_m(), g.south_m(), g.east_m(), g.north_m(), kTileCells,
                   files.tiles.levels};
  for (const std::string& plot : files.plots) products.plots[plot] = file_bytes(dir / plot);
  return products;
}

}  // namespace bathyslam::server
