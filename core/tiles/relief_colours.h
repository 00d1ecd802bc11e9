#pragma once
// The colours of elevation everywhere the map is drawn (the report's quicklook, the HTTP
// endpoint's XYZ tiles): a turbo ramp from deep to shallow between two quantiles of the map,
// darkened by a hillshade lit from the north-west.
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

}  // namespace bathyslam
