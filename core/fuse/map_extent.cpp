#include "core/fuse/map_extent.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/types/format.h"

namespace bathyslam {

double sounding_reach_m(std::span<const Beam> beams) {
  double reach = 0;
  for (const Beam& beam : beams) reach = std::max(reach, std::hypot(double{beam.along}, double{beam.across}));
  return reach;
}

MapExtent map_extent(const std::vector<NavSample>& nav, double reach_m, double resolution_m) {
  MapExtent extent;
  if (nav.empty() || !(resolution_m > 0)) return extent;
  const auto [west, east] =
      std::minmax_element(nav.begin(), nav.end(), [](const NavSample& a, const NavSample& b) { return a.easting < b.easting; });
  const auto [south, north] = std::minmax_element(
      nav.begin(), nav.end(), [](const NavSample& a, const NavSample& b) { return a.northing < b.northing; });
  extent.width_m = east->easting - west->easting + 2 * reach_m;
  extent.height_m = north->northing - south->northing + 2 * reach_m;
  // One more cell each way: the box's edges need not fall on the lattice.
  const double cells = (std::ceil(extent.width_m / resolution_m) + 1) * (std::ceil(extent.height_m / resolution_m) + 1);
  constexpr double kMax = static_cast<double>(std::numeric_limits<std::uint64_t>::max());
  extent.cells = cells >= kMax ? std::numeric_limits<std::uint64_t>::max() : static_cast<std::uint64_t>(cells);
  return extent;
}

std::optional<Problem> map_extent_problem(const MapExtent& extent, double resolution_m, std::uint64_t max_cells) {
  if (extent.cells <= max_cells) return std::nullopt;
  return Problem{Problem::Severity::kError, "nav.csv", 0, "easting, northing",
                 format("the survey covers %.0f m × %.0f m: a map of %llu cells at %g m, over the limit of %llu",
                        extent.width_m, extent.height_m, static_cast<unsigned long long>(extent.cells), resolution_m,
                        static_cast<unsigned long long>(max_cells))};
}

}  // namespace bathyslam
