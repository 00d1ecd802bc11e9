#pragma once
// The colours of elevation everywhere the map is drawn (the report's quicklook, the HTTP
// endpoint's XYZ tiles): a turbo ramp from deep to shallow between two quantiles of the map,
// darkened by a hillshade lit from the north-west.
#include <cmath>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace bathyslam {

using Ramp = std::vector<cv::Vec3b>;  // 256 BGR colours from the low end to the high end

Ramp turbo_ramp();
const cv::Vec3b& colour_of(const Ramp& ramp, double value, double lo, double hi);

// The q-quantiles (0..1) of the finite values; {0, 1} when there are none (hi > lo always).
std::pair<double, double> quantile_range(std::vector<float> values, double q_lo, double q_hi);

// Lambertian shade (0..1) of a surface with these slopes (dz/de, dz/dn), exaggerated 3x (survey
// relief is metres over hundreds of metres), lit from azimuth 315° at 45°.
double lambert_shade(double slope_east, double slope_north);
// The light a shade lets through: a floor of ambient light keeps slopes facing away coloured.
inline double light_of(double shade) { return 0.35 + 0.65 * shade; }

// The slope across a cell from its neighbours `step` away: central, one-sided beside a cell
// without data (NaN), flat where both lack it.
inline double slope_between(float before, float here, float after, double step) {
  if (!std::isnan(before) && !std::isnan(after)) return (after - before) / (2 * step);
  if (!std::isnan(after)) return (after - here) / step;
  if (!std::isnan(before)) return (here - before) / step;
  return 0.0;
}

// lambert_shade at cell (x, y) of a north-up raster (row 0 north) whose `elevation(x, y)` is NaN
// outside it and where it has no data, its cells `step_east` by `step_north` apart.
template <typename Elevation>
double shade_at(const Elevation& elevation, int x, int y, double step_east, double step_north) {
  const float here = elevation(x, y);
  return lambert_shade(slope_between(elevation(x - 1, y), here, elevation(x + 1, y), step_east),
                       slope_between(elevation(x, y + 1), here, elevation(x, y - 1), step_north));
}

}  // namespace bathyslam
