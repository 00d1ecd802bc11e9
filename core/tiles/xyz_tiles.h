#pragma once
// tiles (XYZ): the map as the tiles every web map and QGIS's "XYZ Tiles" layer read: 256 x 256
// PNGs in Web Mercator (EPSG:3857), z/x/y with y from the north. Each is drawn from the job's
// COG at the zoom's resolution (GDAL picks the COG's overview), its elevation on the report's
// ramp and hillshade (relief_colours.h), transparent where the map has no data.
#include <array>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

class GDALDataset;

namespace bathyslam {

inline constexpr int kXyzTileSide = 256;
inline constexpr int kXyzMaxZoom = 24;  // 2.4 cm a pixel at the equator

// A tile's corners in EPSG:3857 metres: west, south, east, north. Throws std::invalid_argument
// for z outside 0..kXyzMaxZoom or x, y outside 0..2^z - 1.
std::array<double, 4> xyz_tile_bounds(int z, int x, int y);
// Web Mercator metres to WGS 84 longitude and latitude, degrees.
std::array<double, 2> mercator_to_lon_lat(double x, double y);

class XyzTileSource {
 public:
  // A COG's bytes (the job's map.tif: elevation in band 1, NaN without data) in its CRS
  // ("EPSG:<code>"). The colour ramp spans the map's 1 % to 99 % elevation, the same in every
  // tile. Throws std::runtime_error when GDAL cannot read them or PROJ cannot place the CRS.
  XyzTileSource(std::vector<std::uint8_t> cog, std::string crs);
  ~XyzTileSource();  // after every tile_png call has returned
  XyzTileSource(const XyzTileSource&) = delete;
  XyzTileSource& operator=(const XyzTileSource&) = delete;

  // The tile as an RGBA PNG; nullopt when the tile does not meet the map. `shade` false: the
  // ramp's colours alone, which a reader can turn back into elevation (ramp_range). Thread-safe.
  std::optional<std::vector<std::uint8_t>> tile_png(int z, int x, int y, bool shade) const;

  // The map's extent in WGS 84: west, south, east, north (degrees).
  const std::array<double, 4>& lon_lat_bounds() const { return bounds_; }
  // The elevations the ramp's first and last colours stand for.
  std::array<double, 2> ramp_range() const { return {lo_, hi_}; }
  // The cell size of the COG (CRS units): the zoom past which tiles only magnify.
  double resolution() const { return resolution_; }
  std::size_t bytes() const { return size_; }

 private:
  struct Closer {
    void operator()(GDALDataset* ds) const;
  };
  using Handle = std::unique_ptr<GDALDataset, Closer>;
  // At most kReaders handles of the COG are open (GDAL's are not thread-safe, and each holds
  // its decompressed blocks and ZSTD buffers: eight concurrent readers peaked at 300 MB on
  // `lake`); a call waits for one, and a handle kept open keeps its blocks for the next tile.
  class Reader;
  static constexpr int kReaders = 2;
  mutable std::mutex mutex_;
  mutable std::condition_variable returned_;
  mutable std::vector<Handle> idle_;
  mutable int lent_ = 0;

  std::string path_;  // the COG in GDAL's /vsimem/
  std::string crs_;
  std::size_t size_ = 0;
  std::array<double, 6> transform_{};
  int width_ = 0, height_ = 0;
  double resolution_ = 0, lo_ = 0, hi_ = 1;
  std::array<double, 4> bounds_{};
};

}  // namespace bathyslam
