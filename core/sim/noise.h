#pragma once
// Smooth random relief shared by the seabed kinds.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "core/sim/terrain.h"

namespace bathyslam::sim {

inline double smoothstep(double edge0, double edge1, double x) {
  const double t = std::clamp((x - edge0) / (edge1 - edge0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// Random values on a square lattice, interpolated smoothly: the building block of the relief.
class ValueNoise {
 public:
  ValueNoise(const Area& area, double spacing_m, double sigma, std::mt19937_64& rng)
      : origin_(area.min), spacing_(spacing_m) {
    cols_ = static_cast<int>(std::ceil((area.max.x() - area.min.x()) / spacing_m)) + 2;
    rows_ = static_cast<int>(std::ceil((area.max.y() - area.min.y()) / spacing_m)) + 2;
    std::normal_distribution<double> normal(0.0, sigma);
    values_.resize(static_cast<std::size_t>(cols_) * rows_);
    for (double& v : values_) v = normal(rng);
  }

  double operator()(double x, double y) const {
    const double u = std::clamp((x - origin_.x()) / spacing_, 0.0, cols_ - 1.001);
    const double v = std::clamp((y - origin_.y()) / spacing_, 0.0, rows_ - 1.001);
    const int i = static_cast<int>(u), j = static_cast<int>(v);
    const double fu = smoothstep(0, 1, u - i), fv = smoothstep(0, 1, v - j);
    auto at = [&](int a, int b) { return values_[static_cast<std::size_t>(b) * cols_ + a]; };
    return (1 - fv) * ((1 - fu) * at(i, j) + fu * at(i + 1, j)) +
           fv * ((1 - fu) * at(i, j + 1) + fu * at(i + 1, j + 1));
  }

 private:
  Eigen::Vector2d origin_;
  double spacing_;
  int cols_ = 0, rows_ = 0;
  std::vector<double> values_;
};

}  // namespace bathyslam::sim
