#include "core/tiles/quicklook.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/tiles/relief_colours.h"

namespace bathyslam {
namespace {

constexpr int kHeader = 40, kFooter = 60;   // title above the map, colour bar below
constexpr int kMinSide = 600, kMaxSide = 3000;  // map pixels on the longer side
const cv::Vec3b kNoData(255, 255, 255), kOneMapOnly(200, 200, 200);

// Blue through white to red (BGR), for signed differences.
Ramp diverging_ramp() {
  const cv::Vec3d blue(192, 76, 59), white(255, 255, 255), red(38, 4, 180);
  Ramp ramp(256);
  for (int i = 0; i < 256; ++i) {
    const double t = (i - 127.5) / 127.5;
    const cv::Vec3d c = t < 0 ? white + (-t) * (blue - white) : white + t * (red - white);
    ramp[i] = cv::Vec3b(cv::saturate_cast<uint8_t>(c[0]), cv::saturate_cast<uint8_t>(c[1]), cv::saturate_cast<uint8_t>(c[2]));
  }
  return ramp;
}

// The hillshade (relief_colours.h) of every cell with data; 1 elsewhere.
cv::Mat hillshade(const GridRaster& map) {
  const GridGeometry& g = map.geometry;
  cv::Mat shade(g.height, g.width, CV_32F, cv::Scalar(1));
  auto z = [&](int x, int y) {
    return x < 0 || y < 0 || x >= g.width || y >= g.height ? NAN : map.elevation[static_cast<std::size_t>(y) * g.width + x];
  };
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      if (!std::isnan(z(x, y))) shade.at<float>(y, x) = static_cast<float>(shade_at(z, x, y, g.resolution_m, g.resolution_m));
    }
  }
  return shade;
}

std::string metres(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f m", v);
  return text;
}

// Title, the map scaled to a legible size (nearest neighbour up, area average down) and a
// colour bar from `lo` to `hi`.
std::vector<std::uint8_t> compose_png(const cv::Mat& map_bgr, const std::string& title, const Ramp& ramp, double lo,
                                      double hi, const std::string& bar_label) {
  const int side = std::max(map_bgr.cols, map_bgr.rows);
  const double scale = std::clamp(1.0, static_cast<double>(kMinSide) / side, static_cast<double>(kMaxSide) / side);
  cv::Mat scaled;
  cv::resize(map_bgr, scaled, cv::Size(), scale, scale, scale > 1 ? cv::INTER_NEAREST : cv::INTER_AREA);
  const int width = std::max(scaled.cols, 420);
  cv::Mat image(kHeader + scaled.rows + kFooter, width, CV_8UC3, cv::Scalar(255, 255, 255));
  scaled.copyTo(image(cv::Rect(0, kHeader, scaled.cols, scaled.rows)));
  const cv::Scalar black(0, 0, 0);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  cv::putText(image, title, {10, 27}, font, 0.6, black, 1, cv::LINE_AA);
  const int bar_y = kHeader + scaled.rows + 12, bar_x = 80;
  for (int i = 0; i < 256; ++i) {
    cv::line(image, {bar_x + i, bar_y}, {bar_x + i, bar_y + 14}, cv::Scalar(ramp[i][0], ramp[i][1], ramp[i][2]));
  }
  cv::rectangle(image, {bar_x, bar_y}, {bar_x + 255, bar_y + 14}, black, 1);
  cv::putText(image, metres(lo), {bar_x - 70, bar_y + 12}, font, 0.4, black, 1, cv::LINE_AA);
  cv::putText(image, metres(hi), {bar_x + 262, bar_y + 12}, font, 0.4, black, 1, cv::LINE_AA);
  cv::putText(image, bar_label, {bar_x, bar_y + 36}, font, 0.45, black, 1, cv::LINE_AA);
  std::vector<std::uint8_t> png;
  if (!cv::imencode(".png", image, png)) throw std::runtime_error("quicklook: PNG encoding failed");
  return png;
}

}  // namespace

std::vector<std::uint8_t> hillshade_png(const GridRaster& map, const std::string& title) {
  const GridGeometry& g = map.geometry;
  if (g.cells() == 0) throw std::invalid_argument("hillshade_png: the map is empty");
  const Ramp ramp = turbo_ramp();
  const auto [lo, hi] = quantile_range(map.elevation, 0.01, 0.99);
  const cv::Mat shade = hillshade(map);
  cv::Mat bgr(g.height, g.width, CV_8UC3);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * g.width + x;
      if (!map.valid(i)) {
        bgr.at<cv::Vec3b>(y, x) = kNoData;
        continue;
      }
      bgr.at<cv::Vec3b>(y, x) = colour_of(ramp, map.elevation[i], lo, hi) * light_of(shade.at<float>(y, x));
    }
  }
  return compose_png(bgr, title, ramp, lo, hi, "elevation (1st to 99th percentile)");
}

std::vector<std::uint8_t> difference_png(const GridRaster& a, const GridRaster& b, const std::string& title) {
  if (a.geometry.resolution_m != b.geometry.resolution_m) {
    throw std::invalid_argument("difference_png: the maps have different resolutions");
  }
  const GridGeometry u = union_of(a.geometry, b.geometry);
  if (u.cells() == 0) throw std::invalid_argument("difference_png: both maps are empty");
  const GridRaster ua = crop(a, u), ub = crop(b, u);
  std::vector<float> difference(u.cells(), NAN);
  for (std::size_t i = 0; i < difference.size(); ++i) {
    if (ua.valid(i) && ub.valid(i)) difference[i] = ua.elevation[i] - ub.elevation[i];
  }
  std::vector<float> magnitude(difference.size());
  std::transform(difference.begin(), difference.end(), magnitude.begin(), [](float d) { return std::fabs(d); });
  const double scale = quantile_range(std::move(magnitude), 0.0, 0.99).second;
  const Ramp ramp = diverging_ramp();
  cv::Mat bgr(u.height, u.width, CV_8UC3);
  for (int y = 0; y < u.height; ++y) {
    for (int x = 0; x < u.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * u.width + x;
      const bool in_a = ua.valid(i), in_b = ub.valid(i);
      bgr.at<cv::Vec3b>(y, x) = in_a && in_b ? colour_of(ramp, difference[i], -scale, scale)
                                : in_a || in_b ? kOneMapOnly
                                               : kNoData;
    }
  }
  return compose_png(bgr, title, ramp, -scale, scale, "elevation difference (99th percentile of |difference|)");
}

}  // namespace bathyslam
