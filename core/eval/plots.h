#pragma once
// PNG plots of the quality report, drawn with OpenCV: labelled axes, one or more series.
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace bathyslam {

struct Series {
  std::string label;
  std::vector<Eigen::Vector2d> points;
  uint8_t r = 0, g = 0, b = 0;
  bool bars = false;  // draw as bars from y = 0 (histograms)
};

struct PlotSpec {
  std::string title;
  std::string x_label;
  std::string y_label;
  bool equal_aspect = false;  // maps: one metre is as long on both axes
};

// The plot as PNG bytes.
std::vector<uint8_t> plot_png(const PlotSpec& spec, const std::vector<Series>& series);

}  // namespace bathyslam
