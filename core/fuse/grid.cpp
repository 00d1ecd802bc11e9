#include "core/fuse/grid.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace bathyslam {

GridGeometry union_of(const GridGeometry& a, const GridGeometry& b) {
  if (a.resolution_m != b.resolution_m) throw std::invalid_argument("union_of: grids of different resolutions");
  if (a.cells() == 0) return b;
  if (b.cells() == 0) return a;
  GridGeometry u = a;
  u.left = std::min(a.left, b.left);
  u.top = std::max(a.top, b.top);
  u.width = static_cast<int>(std::max(a.right(), b.right()) - u.left + 1);
  u.height = static_cast<int>(u.top - std::min(a.bottom(), b.bottom()) + 1);
  return u;
}

GridRaster GridRaster::no_data(const GridGeometry& geometry) {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  GridRaster r;
  r.geometry = geometry;
  r.elevation.assign(geometry.cells(), kNaN);
  r.uncertainty.assign(geometry.cells(), kNaN);
  r.count.assign(geometry.cells(), kNaN);
  return r;
}

std::size_t GridRaster::valid_cells() const {
  return static_cast<std::size_t>(std::count_if(count.begin(), count.end(), [](float c) { return !std::isnan(c); }));
}

GridRaster crop(const GridRaster& source, const GridGeometry& window) {
  const GridGeometry& g = source.geometry;
  if (g.resolution_m != window.resolution_m) throw std::invalid_argument("crop: grids of different resolutions");
  GridRaster out = GridRaster::no_data(window);
  const std::int64_t col_lo = std::max(g.left, window.left), col_hi = std::min(g.right(), window.right());
  const std::int64_t row_lo = std::max(g.bottom(), window.bottom()), row_hi = std::min(g.top, window.top);
  if (col_lo > col_hi) return out;
  const auto run = static_cast<std::ptrdiff_t>(col_hi - col_lo + 1);
  for (std::int64_t row = row_hi; row >= row_lo; --row) {
    const std::size_t from = g.index(col_lo, row), to = window.index(col_lo, row);
    std::copy_n(source.elevation.begin() + from, run, out.elevation.begin() + to);
    std::copy_n(source.uncertainty.begin() + from, run, out.uncertainty.begin() + to);
    std::copy_n(source.count.begin() + from, run, out.count.begin() + to);
  }
  return out;
}

}  // namespace bathyslam
