#pragma once
// GeoTIFF export through GDAL's COG driver (cloud-optimised GeoTIFF): Float32 bands elevation,
// uncertainty and count, NaN NoData, the survey's CRS, a geotransform on the cell edges, internal
// 512 × 512 tiles, ZSTD with the floating-point predictor, and averaged overviews when the raster
// is larger than one tile.
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include "core/fuse/grid.h"

namespace bathyslam {

// Writes `raster` (cells in `crs`, an "EPSG:<code>") to `path`; throws std::runtime_error naming
// the path when GDAL cannot.
void write_geotiff(const GridRaster& raster, std::string_view crs, const std::filesystem::path& path);

// A Float32 band of a raster and its name.
struct NamedBand {
  const char* name;
  const std::vector<float>* values;  // geometry.cells() values, north-up rows
};

// The same for any Float32 bands of `geometry`, NaN NoData.
void write_geotiff(const GridGeometry& geometry, std::span<const NamedBand> bands, std::string_view crs,
                   const std::filesystem::path& path);

}  // namespace bathyslam
