#include "core/fuse/map_extent.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/types/format.h"

namespace bathyslam {

MapExtent survey_map_extent(const Survey& survey, double resolution_m) {
  MapExtent extent;
  if (survey.nav.empty() || !(resolution_m > 0)) return extent;
  double reach = 0;  // how far from the vehicle a sounding can land, horizontally
  for (const Beam& beam : survey.beams) reach = std::max(reach, std::hypot(double{beam.along}, double{beam.across}));
  const auto [west, east] = std::minmax_element(survey.nav.begin(), survey.nav.end(),
                                                [](const NavSample& a, const NavSample& b) { return a.easting < b.easting; });
  const auto [south, north] = std::minmax_element(
      survey.nav.begin(), survey.nav.end(), [](const NavSample& a, const NavSample& b) { return a.northing < b.northing; });
  extent.width_m = east->easting - west->easting + 2 * reach;
  extent.height_m = north->northing - south->northing + 2 * reach;
  // One more cell each way: the box's edges need not fall on the lattice.
  const double cells = (std::ceil(extent.width_m / resolution_m) + 1) * (std::ceil(extent.height_m / resolution_m) + 1);
  constexpr double kMax = static_cast<double>(std::numeric_limits<std::uint64_t>::max());
  extent.cells = cells >= kMax ? std::numeric_limits<std::uint64_t>::max() : static_cast<std::uint64_t>(cells);
  return extent;
}

std::optional<Problem> map_extent_problem(const Survey& survey, double resolution_m, std::uint64_t max_cells) {
  const MapExtent extent = survey_map_extent(survey, resolution_m);
  if (extent.cells <= max_cells) return std::nullopt;
  return Problem{Problem::Severity::kError, "nav.csv", 0, "easting, northing",
                 format("the survey covers %.0f m × %.0f m: a map of %llu cells at %g m, over the limit of %llu",
                        extent.width_m, extent.height_m, static_cast<unsigned long long>(extent.cells), resolution_m,
                        static_cast<unsigned long long>(max_cells))};
}

}  // namespace bathyslam
