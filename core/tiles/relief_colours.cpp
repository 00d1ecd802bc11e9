#include "core/tiles/relief_colours.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace bathyslam {

Ramp turbo_ramp() {
  cv::Mat levels(1, 256, CV_8U), colours;
  for (int i = 0; i < 256; ++i) levels.at<uint8_t>(i) = static_cast<uint8_t>(i);
  cv::applyColorMap(levels, colours, cv::COLORMAP_TURBO);
  return Ramp(colours.begin<cv::Vec3b>(), colours.end<cv::Vec3b>());
}

const cv::Vec3b& colour_of(const Ramp& ramp, double value, double lo, double hi) {
  const double t = std::clamp((value - lo) / (hi - lo), 0.0, 1.0);
  return ramp[static_cast<int>(std::lround(t * 255))];
}

std::pair<double, double> quantile_range(std::vector<float> values, double q_lo, double q_hi) {
  std::erase_if(values, [](float v) { return !std::isfinite(v); });
  if (values.empty()) return {0, 1};
  auto at = [&](double q) {
    auto it = values.begin() + static_cast<std::ptrdiff_t>(q * (values.size() - 1));
    std::nth_element(values.begin(), it, values.end());
    return static_cast<double>(*it);
  };
  double lo = at(q_lo), hi = at(q_hi);
  if (hi - lo < 1e-3) hi = lo + 1e-3;
  return {lo, hi};
}

double lambert_shade(double slope_east, double slope_north) {
  constexpr double kExaggeration = 3;
  const cv::Vec3d light(-0.5, 0.5, std::sqrt(0.5));  // east, north, up
  const cv::Vec3d normal = cv::normalize(cv::Vec3d(-kExaggeration * slope_east, -kExaggeration * slope_north, 1));
  return std::max(0.0, normal.dot(light));
}

}  // namespace bathyslam
