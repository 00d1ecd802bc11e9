#pragma once
// The raster a survey's map would need, known before any fusion: the navigation's bounding box
// widened by the sonar's reach, in cells of the map's resolution. Fusion keeps only touched
// cells, but the map it returns is one dense raster over that box, so a survey with a single
// stray position 500 km away asks for a trillion cells; this is how it is refused first.
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "core/io/problem.h"
#include "core/types/survey.h"

namespace bathyslam {

struct MapExtent {
  double width_m = 0, height_m = 0;
  std::uint64_t cells = 0;  // saturates instead of overflowing
};

// How far from the vehicle a ping's soundings land, horizontally.
double sounding_reach_m(std::span<const Beam> beams);

// The extent of a survey with navigation `nav` whose soundings land up to `reach_m` from it.
MapExtent map_extent(const std::vector<NavSample>& nav, double reach_m, double resolution_m);

// An error naming nav.csv's easting and northing when the map would need more than `max_cells`.
std::optional<Problem> map_extent_problem(const MapExtent& extent, double resolution_m, std::uint64_t max_cells);

}  // namespace bathyslam
