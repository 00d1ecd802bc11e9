#include "core/tiles/gdal_raster.h"

#include <array>
#include <cerrno>
#include <mutex>

#include <cpl_error.h>
#include <ogr_spatialref.h>

#include "core/io/file_bytes.h"

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

namespace {

bool disk_full(int error_number) { return error_number == ENOSPC || error_number == EDQUOT || error_number == EFBIG; }

// GDAL's errors while it writes one file, on this thread: the first that came right after a write
// the disk refused (its errno, read before anything else can change it), each passed on to GDAL's
// default handler as before. errno after the whole copy is not enough: a refused write is often
// followed by failing reads of the half-written file, which leave errno of their own.
class DiskFullWatch {
 public:
  DiskFullWatch() { CPLPushErrorHandlerEx(&DiskFullWatch::handle, this); }
  ~DiskFullWatch() { CPLPopErrorHandler(); }
  DiskFullWatch(const DiskFullWatch&) = delete;
  DiskFullWatch& operator=(const DiskFullWatch&) = delete;
  int error_number() const { return error_number_; }

 private:
  static void CPL_STDCALL handle(CPLErr level, CPLErrorNum number, const char* message) {
    const int now = errno;
    auto* self = static_cast<DiskFullWatch*>(CPLGetErrorHandlerUserData());
    if (level >= CE_Failure && self->error_number_ == 0 && disk_full(now)) self->error_number_ = now;
    CPLDefaultErrorHandler(level, number, message);
  }
  int error_number_ = 0;
};

}  // namespace

GdalDatasetPtr copy_to_file(const char* driver, const std::filesystem::path& path, GDALDataset& source,
                            char** options, const std::string& what) {
  CPLErrorReset();
  GdalDatasetPtr copy;
  int refused = 0;
  {
    const DiskFullWatch watch;
    errno = 0;
    copy.reset(gdal_driver(driver)->CreateCopy(path.c_str(), &source, FALSE, options, nullptr, nullptr));
    refused = watch.error_number();
    if (!copy && refused == 0 && disk_full(errno)) refused = errno;
  }
  if (!copy && refused != 0) throw WriteError(path, refused);
  if (!copy) throw gdal_error(what, std::string(driver) + " driver");
  return copy;
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
