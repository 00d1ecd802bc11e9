#pragma once
// What the GDAL-based raster writers share: the driver lookup and a grid assembled in GDAL's
// memory driver (geotransform, CRS, named bands), ready to be copied by a format's driver.
#include <filesystem>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <gdal_priv.h>

#include "core/fuse/grid.h"
#include "core/tiles/geotiff_writer.h"  // NamedBand

namespace bathyslam {

struct GdalDatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }
};
using GdalDatasetPtr = std::unique_ptr<GDALDataset, GdalDatasetCloser>;

// The driver called `name`, registering GDAL's drivers on first use; throws if GDAL lacks it.
GDALDriver* gdal_driver(const char* name);

// A MEM dataset of `geometry` in `crs` ("EPSG:<code>") holding `bands`, NoData `no_data`.
// Throws std::runtime_error starting with `what` (the file being written and its format).
GdalDatasetPtr memory_raster(const GridGeometry& geometry, std::string_view crs, std::span<const NamedBand> bands,
                             double no_data, const std::string& what);

// std::runtime_error "<what>: <why> (<GDAL's last error>)".
std::runtime_error gdal_error(const std::string& what, const std::string& why);

// `source` copied to `path` by the driver called `driver` with `options`. GDAL says a refused
// write in words only; the errno its refused write left says whether the disk was full, which is
// the machine's shortage (WriteError: a job is given back), not a fault of the map (gdal_error).
GdalDatasetPtr copy_to_file(const char* driver, const std::filesystem::path& path, GDALDataset& source,
                            char** options, const std::string& what);

}  // namespace bathyslam
