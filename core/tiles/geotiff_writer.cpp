#include "core/tiles/geotiff_writer.h"

#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

namespace bathyslam {
namespace {

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

GDALDriver* driver(const char* name) {
  static std::once_flag registered;
  std::call_once(registered, [] { GDALAllRegister(); });
  GDALDriver* d = GetGDALDriverManager()->GetDriverByName(name);
  if (d == nullptr) throw std::runtime_error(std::string("GDAL has no ") + name + " driver");
  return d;
}

std::runtime_error write_error(const std::filesystem::path& path, const std::string& what) {
  return std::runtime_error(path.string() + ": cannot write GeoTIFF: " + what + " (" + CPLGetLastErrorMsg() + ")");
}

}  // namespace

void write_geotiff(const GridRaster& raster, std::string_view crs, const std::filesystem::path& path) {
  const GridGeometry& g = raster.geometry;
  if (g.cells() == 0) throw write_error(path, "the grid is empty");

  // The COG driver only copies, so the bands are first assembled in memory.
  DatasetPtr mem(driver("MEM")->Create("", g.width, g.height, 3, GDT_Float32, nullptr));
  if (!mem) throw write_error(path, "MEM dataset");
  // North-up, on the cell edges: GDAL's pixel-is-area convention puts (west, north) at the
  // outer corner of cell (0, 0).
  std::array<double, 6> transform{g.west_m(), g.resolution_m, 0, g.north_m(), 0, -g.resolution_m};
  mem->SetGeoTransform(transform.data());
  OGRSpatialReference srs;
  if (srs.SetFromUserInput(std::string(crs).c_str()) != OGRERR_NONE) throw write_error(path, "unknown CRS '" + std::string(crs) + "'");
  mem->SetSpatialRef(&srs);

  const std::array<std::pair<const char*, const std::vector<float>*>, 3> bands{
      {{"elevation", &raster.elevation}, {"uncertainty", &raster.uncertainty}, {"count", &raster.count}}};
  for (int b = 0; b < 3; ++b) {
    GDALRasterBand* band = mem->GetRasterBand(b + 1);
    band->SetDescription(bands[b].first);
    band->SetNoDataValue(std::nan(""));
    if (band->RasterIO(GF_Write, 0, 0, g.width, g.height, const_cast<float*>(bands[b].second->data()), g.width,
                       g.height, GDT_Float32, 0, 0, nullptr) != CE_None) {
      throw write_error(path, std::string("band ") + bands[b].first);
    }
  }
  mem->SetMetadataItem("AREA_OR_POINT", "Area");

  CPLStringList options;
  options.SetNameValue("BLOCKSIZE", "512");
  options.SetNameValue("COMPRESS", "ZSTD");
  options.SetNameValue("PREDICTOR", "FLOATING_POINT");
  options.SetNameValue("OVERVIEW_COMPRESS", "ZSTD");
  options.SetNameValue("OVERVIEW_PREDICTOR", "FLOATING_POINT");
  options.SetNameValue("OVERVIEW_RESAMPLING", "AVERAGE");  // NoData-aware, like the tile pyramid
  CPLErrorReset();
  DatasetPtr cog(driver("COG")->CreateCopy(path.c_str(), mem.get(), FALSE, options.List(), nullptr, nullptr));
  if (!cog) throw write_error(path, "COG driver");
}

}  // namespace bathyslam
