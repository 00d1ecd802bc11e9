#include "core/eval/plots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace bathyslam {
namespace {

constexpr int kWidth = 900, kHeight = 600;
constexpr int kLeft = 90, kRight = 30, kTop = 50, kBottom = 70;

// A "nice" tick step (1, 2 or 5 times a power of ten) giving about `count` ticks over `span`.
double tick_step(double span, int count) {
  const double raw = span / count;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0}) {
    if (m * magnitude >= raw) return m * magnitude;
  }
  return 10.0 * magnitude;
}

std::string tick_label(double v, double step) {
  char text[32];
  const int decimals = step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(step)));
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  return text;
}

}  // namespace

std::vector<uint8_t> plot_png(const PlotSpec& spec, const std::vector<Series>& series) {
  Eigen::Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  for (const Series& s : series) {
    for (const Eigen::Vector2d& p : s.points) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    if (s.bars) lo.y() = std::min(lo.y(), 0.0);
  }
  if (!std::isfinite(lo.x())) lo = hi = Eigen::Vector2d::Zero();
  for (int a = 0; a < 2; ++a) {
    if (hi[a] - lo[a] < 1e-9) {
      lo[a] -= 0.5;
      hi[a] += 0.5;
    }
  }
  const double plot_w = kWidth - kLeft - kRight, plot_h = kHeight - kTop - kBottom;
  if (spec.equal_aspect) {  // widen the narrower axis around its centre
    const double scale = std::max((hi.x() - lo.x()) / plot_w, (hi.y() - lo.y()) / plot_h);
    const Eigen::Vector2d centre = 0.5 * (lo + hi);
    const Eigen::Vector2d half(0.5 * scale * plot_w, 0.5 * scale * plot_h);
    lo = centre - half;
    hi = centre + half;
  }
  auto to_pixel = [&](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>(kLeft + (p.x() - lo.x()) / (hi.x() - lo.x()) * plot_w),
                     static_cast<int>(kTop + plot_h - (p.y() - lo.y()) / (hi.y() - lo.y()) * plot_h));
  };

  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Scalar black(0, 0, 0), grey(200, 200, 200);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  // Grid, ticks and tick labels.
  const double sx = tick_step(hi.x() - lo.x(), 8), sy = tick_step(hi.y() - lo.y(), 6);
  for (double x = std::ceil(lo.x() / sx) * sx; x <= hi.x(); x += sx) {
    const cv::Point p = to_pixel({x, lo.y()});
    cv::line(image, {p.x, kTop}, {p.x, kTop + static_cast<int>(plot_h)}, grey, 1);
    cv::putText(image, tick_label(x, sx), {p.x - 15, p.y + 20}, font, 0.45, black, 1, cv::LINE_AA);
  }
  for (double y = std::ceil(lo.y() / sy) * sy; y <= hi.y(); y += sy) {
    const cv::Point p = to_pixel({lo.x(), y});
    cv::line(image, {kLeft, p.y}, {kLeft + static_cast<int>(plot_w), p.y}, grey, 1);
    cv::putText(image, tick_label(y, sy), {5, p.y + 5}, font, 0.45, black, 1, cv::LINE_AA);
  }
  cv::rectangle(image, {kLeft, kTop}, {kLeft + static_cast<int>(plot_w), kTop + static_cast<int>(plot_h)}, black, 1);

  for (const Series& s : series) {
    const cv::Scalar colour(s.b, s.g, s.r);
    if (s.bars) {
      const double width = s.points.size() > 1 ? s.points[1].x() - s.points[0].x() : 1.0;
      for (const Eigen::Vector2d& p : s.points) {
        cv::rectangle(image, to_pixel({p.x(), 0.0}), to_pixel({p.x() + width, p.y()}), colour, cv::FILLED);
      }
    } else {
      std::vector<cv::Point> line;
      for (const Eigen::Vector2d& p : s.points) line.push_back(to_pixel(p));
      cv::polylines(image, line, false, colour, 2, cv::LINE_AA);
    }
  }
  // Legend, title and axis labels.
  int legend_y = kTop + 20;
  for (const Series& s : series) {
    if (s.label.empty()) continue;
    const int x = kLeft + static_cast<int>(plot_w) - 230;
    cv::rectangle(image, {x, legend_y - 10}, {x + 20, legend_y}, cv::Scalar(s.b, s.g, s.r), cv::FILLED);
    cv::putText(image, s.label, {x + 28, legend_y}, font, 0.5, black, 1, cv::LINE_AA);
    legend_y += 22;
  }
  cv::putText(image, spec.title, {kLeft, 32}, font, 0.7, black, 2, cv::LINE_AA);
  cv::putText(image, spec.x_label, {kLeft + static_cast<int>(plot_w) / 2 - 80, kHeight - 20}, font, 0.55, black, 1,
              cv::LINE_AA);
  cv::Mat y_label(30, static_cast<int>(plot_h), CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(y_label, spec.y_label, {10, 22}, font, 0.55, black, 1, cv::LINE_AA);
  cv::rotate(y_label, y_label, cv::ROTATE_90_COUNTERCLOCKWISE);
  y_label.copyTo(image(cv::Rect(50, kTop, 30, static_cast<int>(plot_h))));

  std::vector<uint8_t> png;
  cv::imencode(".png", image, png);
  return png;
}

}  // namespace bathyslam
