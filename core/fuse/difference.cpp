#include "core/fuse/difference.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/submaps/joined_surveys.h"
#include "core/types/median.h"

namespace bathyslam {
namespace {

// 1.4826 · median |x|: the spread of the bulk about zero, whatever the few outliers. About zero,
// not about the median: a registration's vertical offset and, on a slope, its horizontal one move
// the bulk, and they are the registration's error as much as its scatter is.
double robust_sigma(const std::vector<double>& v) {
  std::vector<double> magnitudes;
  magnitudes.reserve(v.size());
  for (double x : v) magnitudes.push_back(std::abs(x));
  return 1.4826 * median(std::move(magnitudes));
}

// The slope (rise over run) of `z` at cell i by central differences where both neighbours have
// data, one-sided where one has; 0 where neither does.
double slope_at(const std::vector<float>& z, const GridGeometry& g, int x, int y) {
  const auto at = [&](int xx, int yy) -> float {
    if (xx < 0 || yy < 0 || xx >= g.width || yy >= g.height) return NAN;
    return z[static_cast<std::size_t>(yy) * g.width + xx];
  };
  const auto derivative = [&](float minus, float centre, float plus) {
    if (!std::isnan(minus) && !std::isnan(plus)) return (plus - minus) / (2 * g.resolution_m);
    if (!std::isnan(plus)) return (plus - centre) / g.resolution_m;
    if (!std::isnan(minus)) return (centre - minus) / g.resolution_m;
    return 0.0;
  };
  const float c = at(x, y);
  return std::hypot(derivative(at(x - 1, y), c, at(x + 1, y)), derivative(at(x, y - 1), c, at(x, y + 1)));
}

// The geometry of the cells both rasters can hold.
GridGeometry intersection(const GridGeometry& a, const GridGeometry& b) {
  GridGeometry g;
  g.resolution_m = a.resolution_m;
  g.left = std::max(a.left, b.left);
  g.top = std::min(a.top, b.top);
  const std::int64_t right = std::min(a.right(), b.right()), bottom = std::max(a.bottom(), b.bottom());
  g.width = static_cast<int>(std::max<std::int64_t>(0, right - g.left + 1));
  g.height = static_cast<int>(std::max<std::int64_t>(0, g.top - bottom + 1));
  return g;
}

// Fits sigma_v² + slope² · sigma_h² to the robust variance of the changes in ten bins of slope.
void fit_registration_sigma(const std::vector<double>& change, const std::vector<double>& slope, DifferenceMap& d) {
  if (change.size() < 50) {
    d.sigma_vertical_m = robust_sigma(change);
    return;
  }
  std::vector<std::size_t> order(change.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return slope[a] < slope[b]; });
  constexpr int kBins = 10;
  Eigen::MatrixXd a(kBins, 2);
  Eigen::VectorXd variance(kBins);
  for (int k = 0; k < kBins; ++k) {
    std::vector<double> bin_change, bin_slope2;
    for (std::size_t i = order.size() * k / kBins; i < order.size() * (k + 1) / kBins; ++i) {
      bin_change.push_back(change[order[i]]);
      bin_slope2.push_back(slope[order[i]] * slope[order[i]]);
    }
    a(k, 0) = 1;
    a(k, 1) = median(bin_slope2);
    variance(k) = std::pow(robust_sigma(bin_change), 2);
  }
  Eigen::Vector2d fit = a.colPivHouseholderQr().solve(variance);
  if (fit(1) < 0) fit = {variance.mean(), 0};  // no slope dependence in these data
  if (fit(0) < 0) fit = {0, (a.col(1).dot(variance)) / a.col(1).squaredNorm()};
  d.sigma_vertical_m = std::sqrt(std::max(0.0, fit(0)));
  d.sigma_horizontal_m = std::sqrt(std::max(0.0, fit(1)));
}

// 4-connected components of significant cells, at least `min_cells` each, largest first.
std::vector<ChangedArea> changed_areas(const DifferenceMap& d, int min_cells) {
  const GridGeometry& g = d.geometry;
  std::vector<char> seen(g.cells(), 0);
  std::vector<ChangedArea> areas;
  const double cell_area = g.resolution_m * g.resolution_m;
  for (std::size_t start = 0; start < g.cells(); ++start) {
    if (seen[start] || !(d.significant[start] == 1.0f)) continue;
    std::vector<std::size_t> stack{start}, cells;
    seen[start] = 1;
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      cells.push_back(i);
      const int x = static_cast<int>(i % g.width), y = static_cast<int>(i / g.width);
      for (const auto [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
        const int xx = x + dx, yy = y + dy;
        if (xx < 0 || yy < 0 || xx >= g.width || yy >= g.height) continue;
        const std::size_t j = static_cast<std::size_t>(yy) * g.width + xx;
        if (!seen[j] && d.significant[j] == 1.0f) {
          seen[j] = 1;
          stack.push_back(j);
        }
      }
    }
    if (static_cast<int>(cells.size()) < min_cells) continue;
    ChangedArea area;
    for (std::size_t i : cells) {
      const int x = static_cast<int>(i % g.width), y = static_cast<int>(i / g.width);
      area.easting += (static_cast<double>(g.left + x) + 0.5) * g.resolution_m / cells.size();
      area.northing += (static_cast<double>(g.top - y) + 0.5) * g.resolution_m / cells.size();
      const double c = d.change[i];
      (c > 0 ? area.gained_m3 : area.lost_m3) += std::abs(c) * cell_area;
      if (std::abs(c) > std::abs(area.largest_change_m)) area.largest_change_m = c;
    }
    area.area_m2 = static_cast<double>(cells.size()) * cell_area;
    areas.push_back(area);
  }
  std::sort(areas.begin(), areas.end(), [](const ChangedArea& a, const ChangedArea& b) { return a.area_m2 > b.area_m2; });
  return areas;
}

// The median of `change` in a window of `window` cells around each cell: medians over windows
// centred on a lattice of half a window, bilinear between them (cells of a window with no change
// do not count; a window with none takes no offset).
std::vector<float> local_offsets(const std::vector<float>& change, const GridGeometry& g, int window) {
  const int step = std::max(1, window / 2);
  const int nx = g.width / step + 2, ny = g.height / step + 2;
  std::vector<double> medians(static_cast<std::size_t>(nx) * ny, 0);
  std::vector<double> values;
  for (int by = 0; by < ny; ++by) {
    for (int bx = 0; bx < nx; ++bx) {
      values.clear();
      const int cx = bx * step, cy = by * step;
      for (int y = std::max(0, cy - window / 2); y < std::min(g.height, cy + window / 2); ++y) {
        for (int x = std::max(0, cx - window / 2); x < std::min(g.width, cx + window / 2); ++x) {
          const float c = change[static_cast<std::size_t>(y) * g.width + x];
          if (!std::isnan(c)) values.push_back(c);
        }
      }
      medians[static_cast<std::size_t>(by) * nx + bx] = median(values);
    }
  }
  std::vector<float> offset(change.size(), NAN);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * g.width + x;
      if (std::isnan(change[i])) continue;
      const int bx = x / step, by = y / step;
      const double fx = double(x - bx * step) / step, fy = double(y - by * step) / step;
      const auto m = [&](int xx, int yy) { return medians[static_cast<std::size_t>(yy) * nx + xx]; };
      offset[i] = static_cast<float>((1 - fy) * ((1 - fx) * m(bx, by) + fx * m(bx + 1, by)) +
                                     fy * ((1 - fx) * m(bx, by + 1) + fx * m(bx + 1, by + 1)));
    }
  }
  return offset;
}

}  // namespace

GridRaster fuse_survey(const SubmapSet& set, std::span<const Eigen::Isometry3d> poses, int survey, const FuseConfig& config) {
  const NodeRange own = survey_submaps(set, survey);
  GridFuser fuser(set.origin, config);
  for (int i = own.begin; i < own.end; ++i) {
    if (set.submaps[i].line >= 0) fuser.add(set.submaps[i].points, poses[i]);
  }
  return fuser.raster();
}

DifferenceMap difference_map(const GridRaster& before, const GridRaster& after, const DifferenceConfig& config) {
  if (before.geometry.resolution_m != after.geometry.resolution_m)
    throw std::invalid_argument("difference: the surfaces' cells differ (" + std::to_string(before.geometry.resolution_m) +
                                " m and " + std::to_string(after.geometry.resolution_m) + " m)");
  DifferenceMap d;
  d.geometry = intersection(before.geometry, after.geometry);
  const GridGeometry& g = d.geometry;
  d.change.assign(g.cells(), NAN);
  d.sigma.assign(g.cells(), NAN);
  d.significant.assign(g.cells(), NAN);
  std::vector<float> surface(g.cells(), NAN);  // before's, for the slope
  std::vector<double> noise(g.cells(), 0);     // both surfaces' standard error squared
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const std::int64_t col = g.left + x, row = g.top - y;
      const std::size_t a = before.geometry.index(col, row), b = after.geometry.index(col, row), i = g.index(col, row);
      if (!before.valid(a) || !after.valid(b)) continue;
      surface[i] = before.elevation[a];
      d.change[i] = after.elevation[b] - before.elevation[a];
      const auto standard_error2 = [](float sigma, float n) { return std::isnan(sigma) ? 0.0 : double(sigma) * sigma / n; };
      noise[i] = standard_error2(before.uncertainty[a], before.count[a]) + standard_error2(after.uncertainty[b], after.count[b]);
    }
  }
  const int window = static_cast<int>(std::lround(config.offset_window_m / g.resolution_m));
  d.offset = window > 0 ? local_offsets(d.change, g, window) : std::vector<float>(g.cells(), 0.0f);
  double offset2 = 0;
  for (std::size_t i = 0; i < g.cells(); ++i) {
    if (std::isnan(d.change[i])) continue;
    d.change[i] -= d.offset[i];
    offset2 += double(d.offset[i]) * d.offset[i];
  }
  std::vector<double> changes, slopes;
  std::vector<double> slope(g.cells(), 0);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * g.width + x;
      if (std::isnan(d.change[i])) continue;
      slope[i] = slope_at(surface, g, x, y);
      changes.push_back(d.change[i]);
      slopes.push_back(slope[i]);
    }
  }
  d.cells_compared = changes.size();
  d.offset_rms_m = d.cells_compared ? std::sqrt(offset2 / d.cells_compared) : 0;
  fit_registration_sigma(changes, slopes, d);
  for (std::size_t i = 0; i < g.cells(); ++i) {
    if (std::isnan(d.change[i])) continue;
    const double sigma = std::sqrt(noise[i] + d.sigma_vertical_m * d.sigma_vertical_m +
                                   std::pow(slope[i] * d.sigma_horizontal_m, 2));
    d.sigma[i] = static_cast<float>(sigma);
    const bool significant = std::abs(d.change[i]) > config.k_sigma * sigma;
    d.significant[i] = significant ? 1.0f : 0.0f;
    d.cells_significant += significant;
  }
  d.areas = changed_areas(d, config.min_cells);
  return d;
}

}  // namespace bathyslam
