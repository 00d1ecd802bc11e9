#pragma once
// Hand-made submaps whose map errors are known: flat patches, and lines of them each off by its
// own pose error.
#include <random>

#include "core/submaps/submap.h"

namespace bathyslam {

// A submap of a flat patch: soundings every 0.25 m over `width` x `length` metres at `z`.
inline Submap flat_patch(int index, int line, double x0, double y0, double width, double length, float z) {
  Submap s;
  s.index = index;
  s.line = line;
  s.dr_pose.translation() = Eigen::Vector3d(x0, y0, 0);
  for (double x = 0.125; x < width; x += 0.25) {
    for (double y = 0.125; y < length; y += 0.25) s.points.emplace_back(x, y, z);
  }
  return s;
}

// Sixteen lines of eight 20 x 20 m submaps each, 10 m apart, so every cell is seen by two lines.
// Each submap sits `tilt` off by a random height and cross-track slope (its pose error: every
// cell of it moves together), and each sounding has `noise` of its own.
inline SubmapSet lines_with_submap_errors(double tilt, double noise, uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  SubmapSet set;
  set.lines.resize(16);
  for (int line = 0; line < 16; ++line) {
    for (int k = 0; k < 8; ++k) {
      const double offset = tilt * unit(random), slope = tilt * unit(random) / 20.0;
      Submap s = flat_patch(line * 8 + k, line, 10.0 * line, 20.0 * k, 20, 20, -10.0f);
      for (Eigen::Vector3f& p : s.points) p.z() += static_cast<float>(offset + slope * p.x() + noise * unit(random));
      set.submaps.push_back(std::move(s));
    }
  }
  return set;
}

}  // namespace bathyslam
