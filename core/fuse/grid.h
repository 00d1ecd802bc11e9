#pragma once
// The bathymetric grid's value types, shared by fusion (which fills a grid) and tiling (which
// cuts and coarsens it).
//
// Every grid of a given resolution sits on one lattice anchored at the CRS's own origin: global
// cell (col, row) covers easting [col·r, (col+1)·r) and northing [row·r, (row+1)·r). Anchoring
// at the CRS rather than at the survey's local origin keeps cell edges on round coordinates, so
// grids of different surveys and the fixed tile grid line up cell for cell.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace bathyslam {

// Floor division for the lattice's negative indices (C++'s `/` truncates towards zero).
constexpr std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  return a / b - ((a % b != 0) && ((a < 0) != (b < 0)) ? 1 : 0);
}

// Which window of the lattice a raster holds. Rasters are stored north-up, as GeoTIFF stores
// them: raster row 0 is the northernmost global row `top`, raster row y is global row top - y.
struct GridGeometry {
  double resolution_m = 0.5;
  std::int64_t left = 0;  // global column of raster column 0 (the west edge)
  std::int64_t top = 0;   // global row of raster row 0 (the north edge)
  int width = 0, height = 0;

  std::int64_t right() const { return left + width - 1; }    // global column of the last column
  std::int64_t bottom() const { return top - height + 1; }   // global row of the last row
  double west_m() const { return static_cast<double>(left) * resolution_m; }
  double east_m() const { return static_cast<double>(right() + 1) * resolution_m; }
  double south_m() const { return static_cast<double>(bottom()) * resolution_m; }
  double north_m() const { return static_cast<double>(top + 1) * resolution_m; }
  std::size_t cells() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
  // The global column / row of the cell holding a CRS easting / northing.
  std::int64_t col_of(double easting) const { return static_cast<std::int64_t>(std::floor(easting / resolution_m)); }
  std::int64_t row_of(double northing) const { return static_cast<std::int64_t>(std::floor(northing / resolution_m)); }
  bool contains(std::int64_t col, std::int64_t row) const {
    return col >= left && col <= right() && row >= bottom() && row <= top;
  }
  // Index into a raster's cell vectors of the global cell (col, row), which must be contained.
  std::size_t index(std::int64_t col, std::int64_t row) const {
    return static_cast<std::size_t>(top - row) * static_cast<std::size_t>(width) +
           static_cast<std::size_t>(col - left);
  }
  bool operator==(const GridGeometry&) const = default;
};

// The smallest geometry holding both (same resolution).
GridGeometry union_of(const GridGeometry& a, const GridGeometry& b);

// Per cell: mean elevation (map-frame up, negative below the datum), the standard deviation of
// the cell's soundings (uncertainty) and their count. Cells without enough soundings hold NaN in
// every band; uncertainty is also NaN for a cell of one sounding. Count is float because the
// exported bands are Float32.
struct GridRaster {
  GridGeometry geometry;
  std::vector<float> elevation, uncertainty, count;

  // A raster of `geometry` with every cell NaN.
  static GridRaster no_data(const GridGeometry& geometry);
  bool valid(std::size_t i) const { return !std::isnan(count[i]); }
  std::size_t valid_cells() const;
};

// The cells of `source` that fall inside `window` (same resolution), NaN elsewhere.
GridRaster crop(const GridRaster& source, const GridGeometry& window);

}  // namespace bathyslam
