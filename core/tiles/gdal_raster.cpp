#include "core/tiles/gdal_raster.h"

#include <array>
#include <mutex>

#include <cpl_error.h>
#include <ogr_spatialref.h>

namespace bathyslam {

GDALDriver* gdal_driver(const char* name) {
  static std::once_flag registered;
  std::call_once(registered, [] { GDALAllRegister(); });
  GDALDriver* d = GetGDALDriverManager()->GetDriverByName(name);
  if (d == nullptr) throw std::runtime_error(std::string("GDAL has no ") + name + " driver");
  return d;
}

std::runtime_error gdal_error(const std::string& what, const std::string& why) {
  return std::runtime_error(what + ": " + why + " (" + CPLGetLastErrorMsg() + ")");
}

GdalDatasetPtr memory_raster(const GridGeometry& g, std::string_view crs, std::span<const NamedBand> bands,
                             double no_data, const std::string& what) {
  if (g.cells() == 0) throw gdal_error(what, "the grid is empty");
  GdalDatasetPtr mem(gdal_driver("MEM")->Create("", g.width, g.height, static_cast<int>(bands.size()), GDT_Float32,
                                                nullptr));
  if (!mem) throw gdal_error(what, "MEM dataset");
  // North-up, on the cell edges: GDAL's pixel-is-area convention puts (west, north) at the
  // outer corner of cell (0, 0).
  std::array<double, 6> transform{g.west_m(), g.resolution_m, 0, g.north_m(), 0, -g.resolution_m};
  mem->SetGeoTransform(transform.data());
  OGRSpatialReference srs;
  if (srs.SetFromUserInput(std::string(crs).c_str()) != OGRERR_NONE) {
    throw gdal_error(what, "unknown CRS '" + std::string(crs) + "'");
  }
  mem->SetSpatialRef(&srs);
  for (std::size_t b = 0; b < bands.size(); ++b) {
    GDALRasterBand* band = mem->GetRasterBand(static_cast<int>(b) + 1);
    band->SetDescription(bands[b].name);
    band->SetNoDataValue(no_data);
    if (band->RasterIO(GF_Write, 0, 0, g.width, g.height, const_cast<float*>(bands[b].values->data()), g.width,
                       g.height, GDT_Float32, 0, 0, nullptr) != CE_None) {
      throw gdal_error(what, std::string("band ") + bands[b].name);
    }
  }
  return mem;
}

}  // namespace bathyslam
