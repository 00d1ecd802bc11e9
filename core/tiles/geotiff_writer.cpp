#include "core/tiles/geotiff_writer.h"

#include "core/tiles/gdal_raster.h"

#include <array>
#include <cmath>
#include <string>

#include <cpl_string.h>

namespace bathyslam {
namespace {

std::string what(const std::filesystem::path& path) { return path.string() + ": cannot write GeoTIFF"; }

}  // namespace

void write_geotiff(const GridRaster& raster, std::string_view crs, const std::filesystem::path& path) {
  const std::array<NamedBand, 3> bands{
      {{"elevation", &raster.elevation}, {"uncertainty", &raster.uncertainty}, {"count", &raster.count}}};
  write_geotiff(raster.geometry, bands, crs, path);
}

void write_geotiff(const GridGeometry& geometry, std::span<const NamedBand> bands, std::string_view crs,
                   const std::filesystem::path& path) {
  // The COG driver only copies, so the bands are first assembled in memory.
  GdalDatasetPtr mem = memory_raster(geometry, crs, bands, std::nan(""), what(path));
  mem->SetMetadataItem("AREA_OR_POINT", "Area");

  CPLStringList options;
  options.SetNameValue("BLOCKSIZE", "512");
  options.SetNameValue("COMPRESS", "ZSTD");
  options.SetNameValue("PREDICTOR", "FLOATING_POINT");
  options.SetNameValue("OVERVIEW_COMPRESS", "ZSTD");
  options.SetNameValue("OVERVIEW_PREDICTOR", "FLOATING_POINT");
  options.SetNameValue("OVERVIEW_RESAMPLING", "AVERAGE");  // NoData-aware, like the tile pyramid
  copy_to_file("COG", path, *mem, options.List(), what(path));
}

}  // namespace bathyslam
