#include "core/tiles/xyz_tiles.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>

#include <cpl_vsi.h>
#include <opencv2/imgcodecs.hpp>

#include "core/io/crs.h"
#include "core/tiles/gdal_raster.h"
#include "core/tiles/relief_colours.h"

namespace bathyslam {
namespace {

constexpr double kEarthRadius = 6378137.0;  // EPSG:3857's sphere
constexpr int kLattice = 16;                // PROJ at every 16th pixel, bilinear between (< 0.01 px here)
constexpr int kRampSide = 512;              // the ramp's quantiles from the map read this small

GdalDatasetPtr open_cog(const std::string& path) {
  gdal_driver("GTiff");  // registers GDAL's drivers
  GdalDatasetPtr ds(GDALDataset::FromHandle(GDALOpen(path.c_str(), GA_ReadOnly)));
  if (!ds || ds->GetRasterCount() < 1) throw gdal_error("map.tif", "not a GeoTIFF GDAL can read");
  return ds;
}

// Band 1 of `ds`, window (col, row, cols, rows), read into a buffer of `width` x `height` cells
// (GDAL takes the COG's overview nearest that size), with its NoData as NaN.
std::vector<float> read_elevation(GDALDataset& ds, int col, int row, int cols, int rows, int width, int height) {
  std::vector<float> values(static_cast<std::size_t>(width) * height);
  GDALRasterBand* band = ds.GetRasterBand(1);
  if (band->RasterIO(GF_Read, col, row, cols, rows, values.data(), width, height, GDT_Float32, 0, 0) != CE_None)
    throw gdal_error("map.tif", "cannot read its elevation");
  int has_no_data = 0;
  const double no_data = band->GetNoDataValue(&has_no_data);
  if (has_no_data && !std::isnan(no_data)) std::replace(values.begin(), values.end(), static_cast<float>(no_data), NAN);
  return values;
}

// This thread's projection of WGS 84 into `crs`: creating one takes PROJ milliseconds and
// memory, using one microseconds, and one may not be shared between threads.
const GeographicProjection& projection_to(const std::string& crs) {
  thread_local std::string held_crs;
  thread_local std::unique_ptr<GeographicProjection> held;
  if (!held || held_crs != crs) {
    held = std::make_unique<GeographicProjection>(crs);
    held_crs = crs;
  }
  return *held;
}

}  // namespace

std::array<double, 4> xyz_tile_bounds(int z, int x, int y) {
  if (z < 0 || z > kXyzMaxZoom) throw std::invalid_argument("z must be within 0.." + std::to_string(kXyzMaxZoom));
  const std::int64_t tiles = std::int64_t{1} << z;
  if (x < 0 || x >= tiles || y < 0 || y >= tiles)
    throw std::invalid_argument("x and y must be within 0.." + std::to_string(tiles - 1) + " at z " + std::to_string(z));
  const double world = 2 * M_PI * kEarthRadius, side = world / static_cast<double>(tiles);
  const double west = -world / 2 + x * side, north = world / 2 - y * side;
  return {west, north - side, west + side, north};
}

std::array<double, 2> mercator_to_lon_lat(double x, double y) {
  return {x / kEarthRadius * 180 / M_PI, (2 * std::atan(std::exp(y / kEarthRadius)) - M_PI / 2) * 180 / M_PI};
}

XyzTileSource::XyzTileSource(std::vector<std::uint8_t> cog, std::string crs) : crs_(std::move(crs)), size_(cog.size()) {
  static std::atomic<int> next{0};
  path_ = "/vsimem/bathyslam-xyz-" + std::to_string(next++) + ".tif";
  auto* buffer = static_cast<GByte*>(VSIMalloc(cog.size()));
  if (!buffer) throw std::runtime_error("map.tif: no memory for " + std::to_string(cog.size()) + " bytes");
  std::memcpy(buffer, cog.data(), cog.size());
  VSIFCloseL(VSIFileFromMemBuffer(path_.c_str(), buffer, cog.size(), TRUE));
  try {
    GdalDatasetPtr ds = open_cog(path_);
    width_ = ds->GetRasterXSize(), height_ = ds->GetRasterYSize();
    if (ds->GetGeoTransform(transform_.data()) != CE_None || transform_[2] != 0 || transform_[4] != 0)
      throw gdal_error("map.tif", "no north-up geotransform");
    resolution_ = transform_[1];
    const double shrink = std::max(1.0, static_cast<double>(std::max(width_, height_)) / kRampSide);
    const int w = std::max(1, static_cast<int>(width_ / shrink)), h = std::max(1, static_cast<int>(height_ / shrink));
    std::tie(lo_, hi_) = quantile_range(read_elevation(*ds, 0, 0, width_, height_, w, h), 0.01, 0.99);
    // The extent in longitude and latitude from points along its edges (a projected rectangle's
    // edges curve in WGS 84).
    const GeographicProjection projection(crs_);
    bounds_ = {180, 90, -180, -90};
    for (int k = 0; k <= kLattice; ++k) {
      for (const auto& [u, v] : {std::pair{k, 0}, {k, kLattice}, {0, k}, {kLattice, k}}) {
        const auto p = projection.inverse(transform_[0] + transform_[1] * width_ * u / kLattice,
                                          transform_[3] + transform_[5] * height_ * v / kLattice);
        bounds_ = {std::min(bounds_[0], p.longitude_deg), std::min(bounds_[1], p.latitude_deg),
                   std::max(bounds_[2], p.longitude_deg), std::max(bounds_[3], p.latitude_deg)};
      }
    }
  } catch (...) {
    VSIUnlink(path_.c_str());
    throw;
  }
}

XyzTileSource::~XyzTileSource() {
  idle_.clear();  // closed before their file goes
  VSIUnlink(path_.c_str());
}

void XyzTileSource::Closer::operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }

// A handle of the COG lent for one read, returned (or closed, when it failed) at its end.
class XyzTileSource::Reader {
 public:
  explicit Reader(const XyzTileSource& source) : source_(source) {
    std::unique_lock lock(source_.mutex_);
    source_.returned_.wait(lock, [&] { return source_.lent_ < kReaders; });
    ++source_.lent_;
    if (!source_.idle_.empty()) {
      handle_ = std::move(source_.idle_.back());
      source_.idle_.pop_back();
    }
    lock.unlock();
    try {
      if (!handle_) handle_ = Handle(open_cog(source_.path_).release());
    } catch (...) {
      give_back();
      throw;
    }
  }
  ~Reader() {
    if (std::uncaught_exceptions() > 0) handle_.reset();  // a failed read's handle is not reused
    give_back();
  }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;
  GDALDataset& operator*() const { return *handle_; }

 private:
  void give_back() {
    {
      const std::lock_guard lock(source_.mutex_);
      --source_.lent_;
      if (handle_) source_.idle_.push_back(std::move(handle_));
    }
    source_.returned_.notify_one();
  }
  const XyzTileSource& source_;
  Handle handle_;
};

std::optional<std::vector<std::uint8_t>> XyzTileSource::tile_png(int z, int x, int y, bool shade) const {
  const auto [west, south, east, north] = xyz_tile_bounds(z, x, y);
  const auto [west_lon, south_lat] = mercator_to_lon_lat(west, south);
  const auto [east_lon, north_lat] = mercator_to_lon_lat(east, north);
  if (east_lon < bounds_[0] || west_lon > bounds_[2] || north_lat < bounds_[1] || south_lat > bounds_[3]) return std::nullopt;

  // Where the tile's lattice points fall in the map's CRS, and the map window they span.
  const GeographicProjection& projection = projection_to(crs_);
  std::vector<GeographicProjection::EastNorth> lattice;
  double e_min = INFINITY, e_max = -INFINITY, n_min = INFINITY, n_max = -INFINITY;
  for (int b = 0; b <= kLattice; ++b) {
    for (int a = 0; a <= kLattice; ++a) {
      const auto [lon, lat] = mercator_to_lon_lat(west + (east - west) * a / kLattice, north - (north - south) * b / kLattice);
      lattice.push_back(projection.forward(lon, lat));
      // Far from the CRS's zone (a zoomed-out tile) PROJ answers infinity: those points take no part.
      if (!std::isfinite(lattice.back().easting) || !std::isfinite(lattice.back().northing)) continue;
      e_min = std::min(e_min, lattice.back().easting), e_max = std::max(e_max, lattice.back().easting);
      n_min = std::min(n_min, lattice.back().northing), n_max = std::max(n_max, lattice.back().northing);
    }
  }
  if (!(e_min <= e_max && n_min <= n_max)) return std::nullopt;
  // Cells of the map, clamped in floating point before any cast to int.
  const auto column = [&](double e) { return std::clamp((e - transform_[0]) / resolution_, -1.0, width_ + 1.0); };
  const auto row_of = [&](double n) { return std::clamp((transform_[3] - n) / resolution_, -1.0, height_ + 1.0); };
  const int col0 = std::max(0, static_cast<int>(std::floor(column(e_min))) - 1);
  const int col1 = std::min(width_, static_cast<int>(std::ceil(column(e_max))) + 1);
  const int row0 = std::max(0, static_cast<int>(std::floor(row_of(n_max))) - 1);
  const int row1 = std::min(height_, static_cast<int>(std::ceil(row_of(n_min))) + 1);
  if (col0 >= col1 || row0 >= row1) return std::nullopt;

  // Read no finer than a tile pixel's ground size: zoomed out, GDAL reads an overview.
  const int cols = col1 - col0, rows = row1 - row0;
  const double shrink = std::max(1.0, (e_max - e_min) / kXyzTileSide / resolution_);
  const int width = std::max(1, static_cast<int>(std::ceil(cols / shrink)));
  const int height = std::max(1, static_cast<int>(std::ceil(rows / shrink)));
  const std::vector<float> elevation = [&] {
    const Reader reader(*this);
    return read_elevation(*reader, col0, row0, cols, rows, width, height);
  }();
  const double step_e = cols * resolution_ / width, step_n = rows * resolution_ / height;
  const double e0 = transform_[0] + col0 * resolution_, n0 = transform_[3] - row0 * resolution_;
  const auto at = [&](int bx, int by) {
    return bx < 0 || by < 0 || bx >= width || by >= height ? NAN : elevation[static_cast<std::size_t>(by) * width + bx];
  };

  static const Ramp ramp = turbo_ramp();
  cv::Mat image(kXyzTileSide, kXyzTileSide, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  constexpr int kCell = kXyzTileSide / kLattice;
  for (int j = 0; j < kXyzTileSide; ++j) {
    const int b = j / kCell;
    const double fv = (j % kCell + 0.5) / kCell;
    for (int i = 0; i < kXyzTileSide; ++i) {
      const int a = i / kCell;
      const double fu = (i % kCell + 0.5) / kCell;
      const auto& p00 = lattice[b * (kLattice + 1) + a];
      const auto& p10 = lattice[b * (kLattice + 1) + a + 1];
      const auto& p01 = lattice[(b + 1) * (kLattice + 1) + a];
      const auto& p11 = lattice[(b + 1) * (kLattice + 1) + a + 1];
      const double e = (1 - fv) * ((1 - fu) * p00.easting + fu * p10.easting) + fv * ((1 - fu) * p01.easting + fu * p11.easting);
      const double n =
          (1 - fv) * ((1 - fu) * p00.northing + fu * p10.northing) + fv * ((1 - fu) * p01.northing + fu * p11.northing);
      const double fx = std::floor((e - e0) / step_e), fy = std::floor((n0 - n) / step_n);
      if (!(fx >= 0 && fx < width && fy >= 0 && fy < height)) continue;  // NaN too: a corner PROJ could not place
      const int bx = static_cast<int>(fx), by = static_cast<int>(fy);
      const float here = at(bx, by);
      if (std::isnan(here)) continue;
      cv::Vec3b colour = colour_of(ramp, here, lo_, hi_);
      if (shade) colour = colour * light_of(shade_at(at, bx, by, step_e, step_n));  // buffer row 0 is north
      image.at<cv::Vec4b>(j, i) = cv::Vec4b(colour[0], colour[1], colour[2], 255);
    }
  }
  std::vector<std::uint8_t> png;
  if (!cv::imencode(".png", image, png)) throw std::runtime_error("XYZ tile: PNG encoding failed");
  return png;
}

}  // namespace bathyslam
