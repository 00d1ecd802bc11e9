#include "core/features/tsd_keypoints.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace bathyslam {
namespace {

double percentile_of_valid(const cv::Mat& values, const cv::Mat& mask, double percentile) {
  std::vector<float> v;
  for (int r = 0; r < values.rows; ++r) {
    for (int c = 0; c < values.cols; ++c) {
      if (mask.at<uint8_t>(r, c)) v.push_back(values.at<float>(r, c));
    }
  }
  if (v.empty()) return INFINITY;
  const auto k = static_cast<std::size_t>(std::floor(percentile / 100.0 * (v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

// Bilinear elevation at a fractional cell position; nullopt-like false outside valid cells.
bool elevation_at(const TerrainGrid& grid, double col, double row, float& out) {
  const int c = static_cast<int>(std::floor(col)), r = static_cast<int>(std::floor(row));
  if (c < 0 || r < 0 || c + 1 >= grid.cols() || r + 1 >= grid.rows()) return false;
  const double fc = col - c, fr = row - r;
  double sum = 0;
  for (int dr = 0; dr < 2; ++dr) {
    for (int dc = 0; dc < 2; ++dc) {
      if (!grid.valid.at<uint8_t>(r + dr, c + dc)) return false;
      sum += (dr ? fr : 1 - fr) * (dc ? fc : 1 - fc) * grid.elevation.at<float>(r + dr, c + dc);
    }
  }
  out = static_cast<float>(sum);
  return true;
}

// Dominant gradient direction around (col, row): the peak of a magnitude- and Gaussian-weighted
// histogram of gradient directions, refined by a parabola through the peak and its neighbours.
double dominant_orientation(const cv::Mat& gx, const cv::Mat& gy, const TerrainGrid& grid, int col, int row,
                            int radius, int bins) {
  std::vector<double> histogram(bins, 0.0);
  const double sigma = 0.5 * radius + 0.5;
  for (int r = row - radius; r <= row + radius; ++r) {
    for (int c = col - radius; c <= col + radius; ++c) {
      if (r < 1 || c < 1 || r >= grid.rows() - 1 || c >= grid.cols() - 1 || !grid.valid.at<uint8_t>(r, c)) continue;
      const double x = gx.at<float>(r, c), y = gy.at<float>(r, c);
      const double weight = std::hypot(x, y) * std::exp(-((r - row) * (r - row) + (c - col) * (c - col)) / (2 * sigma * sigma));
      const double angle = std::atan2(y, x) + M_PI;  // [0, 2 pi]
      histogram[static_cast<int>(angle / (2 * M_PI) * bins) % bins] += weight;
    }
  }
  const int peak = static_cast<int>(std::max_element(histogram.begin(), histogram.end()) - histogram.begin());
  const double left = histogram[(peak + bins - 1) % bins], right = histogram[(peak + 1) % bins];
  const double denominator = left - 2 * histogram[peak] + right;
  const double offset = denominator != 0 ? 0.5 * (left - right) / denominator : 0.0;
  return (peak + 0.5 + offset) * 2 * M_PI / bins - M_PI;
}

}  // namespace

cv::Mat terrain_standard_deviation(const TerrainGrid& grid, int window) {
  cv::Mat mask, h, h2, n, sum, sum2;
  grid.valid.convertTo(mask, CV_64F);
  grid.elevation.convertTo(h, CV_64F);
  h = h.mul(mask);
  h2 = h.mul(h);
  const cv::Size size(window, window);
  cv::boxFilter(mask, n, -1, size, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  cv::boxFilter(h, sum, -1, size, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  cv::boxFilter(h2, sum2, -1, size, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  cv::Mat tsd = cv::Mat::zeros(grid.rows(), grid.cols(), CV_32F);
  const double min_cells = 0.5 * window * window;
  for (int r = 0; r < grid.rows(); ++r) {
    for (int c = 0; c < grid.cols(); ++c) {
      const double count = n.at<double>(r, c);
      if (!grid.valid.at<uint8_t>(r, c) || count < min_cells) continue;
      const double mean = sum.at<double>(r, c) / count;
      tsd.at<float>(r, c) = static_cast<float>(std::sqrt(std::max(0.0, sum2.at<double>(r, c) / count - mean * mean)));
    }
  }
  return tsd;
}

std::optional<std::string> descriptor_size_fault(int descriptor_size) {
  if (descriptor_size % 2 != 0) return std::nullopt;
  return "is even; the descriptor is centred on its keypoint, so its side must be odd";
}

std::vector<Keypoint> detect_keypoints(const TerrainGrid& grid, const KeypointConfig& config) {
  if (const auto fault = descriptor_size_fault(config.descriptor_size)) {
    throw std::invalid_argument("keypoints.descriptor_size: " + std::to_string(config.descriptor_size) + " " + *fault);
  }
  std::vector<Keypoint> keypoints;
  if (grid.rows() < 3 || grid.cols() < 3 || config.window_scales.empty()) return keypoints;
  std::vector<cv::Mat> tsd;
  std::vector<double> threshold;
  for (int window : config.window_scales) {
    tsd.push_back(terrain_standard_deviation(grid, window));
    threshold.push_back(percentile_of_valid(tsd.back(), grid.valid, config.percentile));
  }
  const cv::Mat& finest = tsd.front();
  cv::Mat local_max;
  const int s = 2 * config.suppression_radius + 1;
  cv::dilate(finest, local_max, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(s, s)));

  cv::Mat gx, gy;
  cv::Sobel(grid.elevation, gx, CV_32F, 1, 0, 3, 1.0 / (8 * grid.cell_m));
  cv::Sobel(grid.elevation, gy, CV_32F, 0, 1, 3, 1.0 / (8 * grid.cell_m));

  const int half = config.descriptor_size / 2;
  for (int r = 0; r < grid.rows(); ++r) {
    for (int c = 0; c < grid.cols(); ++c) {
      if (!grid.valid.at<uint8_t>(r, c)) continue;
      const float t = finest.at<float>(r, c);
      if (t < config.min_tsd_m || (config.suppression_radius > 0 && t < local_max.at<float>(r, c))) continue;
      bool significant = true;
      for (std::size_t k = 0; k < tsd.size() && significant; ++k) significant = tsd[k].at<float>(r, c) >= threshold[k];
      if (!significant) continue;

      Keypoint kp;
      kp.orientation_rad = dominant_orientation(gx, gy, grid, c, r, half, config.orientation_bins);
      kp.descriptor.resize(config.descriptor_size * config.descriptor_size);
      const double cos_o = std::cos(kp.orientation_rad), sin_o = std::sin(kp.orientation_rad);
      bool complete = true;
      int k = 0;
      for (int v = -half; v <= half && complete; ++v) {
        for (int u = -half; u <= half && complete; ++u) {
          // Descriptor axes turned to the dominant orientation: the same ground seen on another
          // heading gives the same samples.
          complete = elevation_at(grid, c + cos_o * u - sin_o * v, r + sin_o * u + cos_o * v, kp.descriptor[k++]);
        }
      }
      if (!complete) continue;  // too close to the swath edge for a full descriptor
      kp.descriptor.array() -= kp.descriptor.mean();
      const Eigen::Vector2d xy = grid.position(c, r);
      kp.position = Eigen::Vector3d(xy.x(), xy.y(), -grid.elevation.at<float>(r, c));
      kp.tsd_m = t;
      keypoints.push_back(std::move(kp));
    }
  }
  return keypoints;
}

CentredDescriptor centred(const Eigen::VectorXf& descriptor) {
  CentredDescriptor c;
  c.values = descriptor.cast<double>().array() - descriptor.cast<double>().mean();
  c.sum_sq = (c.values * c.values).sum();
  return c;
}

double descriptor_ncc(const CentredDescriptor& a, const CentredDescriptor& b) {
  const double denominator = std::sqrt(a.sum_sq * b.sum_sq);
  return denominator > 0 ? (a.values * b.values).sum() / denominator : 0.0;
}

double descriptor_ncc(const Eigen::VectorXf& a, const Eigen::VectorXf& b) {
  return descriptor_ncc(centred(a), centred(b));
}

double descriptor_mse(const Eigen::VectorXf& a, const Eigen::VectorXf& b, double bound) {
  // The sum of squares only grows: once past the bound it stays there.
  // Blocks of 16 that Eigen vectorises, the bound tested after each (the loop one element at a
  // time was 14 % of a job's CPU: matching tests every keypoint within 30 m).
  const Eigen::Index n = a.size();
  const double limit = bound * static_cast<double>(n);
  double sum = 0;
  for (Eigen::Index start = 0; start < n; start += 16) {
    const Eigen::Index length = std::min<Eigen::Index>(16, n - start);
    sum += (a.segment(start, length) - b.segment(start, length)).cast<double>().squaredNorm();
    if (sum >= limit) break;
  }
  return sum / static_cast<double>(n);
}

}  // namespace bathyslam
