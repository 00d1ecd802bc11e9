#pragma once
// Quicklook images of fused grids (PNG bytes, drawn with OpenCV), for the quality report.
#include <cstdint>
#include <string>
#include <vector>

#include "core/fuse/grid.h"

namespace bathyslam {

// Elevation coloured by a ramp (deep blue to shallow red), shaded by a hillshade lit from the
// north-west, with a colour bar. Cells without data are white.
std::vector<std::uint8_t> hillshade_png(const GridRaster& map, const std::string& title);

// a − b (elevation) over the union of both maps, on a diverging ramp (blue: a deeper than b, red:
// a shallower), symmetric about 0 and scaled to the 99th percentile of |a − b|. Cells with data in
// only one map are grey. Both maps must share the resolution; throws std::invalid_argument if not.
std::vector<std::uint8_t> difference_png(const GridRaster& a, const GridRaster& b, const std::string& title);

}  // namespace bathyslam
