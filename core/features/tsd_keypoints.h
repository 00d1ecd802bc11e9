#pragma once
// features (Algorithm 1): terrain standard deviation (TSD) keypoints of a gridded submap and
// their rotation-normalised elevation descriptors.
#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "core/features/terrain_grid.h"

namespace bathyslam {

struct KeypointConfig {  // Table 1 (b)
  std::array<int, 3> window_scales{3, 7, 9};  // TSD windows, cells
  double percentile = 70;                   // keypoints pass this percentile at every scale
  int descriptor_size = 11;                 // d x d elevation samples, d odd (centred on the keypoint)
  // A departure from the paper: a per-submap percentile alone selects 30 % of the cells, flat
  // or not, so keypoints must also stand above the sounding noise of a flat bottom
  // (docs/slam-core.md, "Departures from Table 1"); without it the feature density could never fall below the switch threshold.
  double min_tsd_m = 0.08;     // at the finest scale
  int suppression_radius = 0;  // cells; 0 (the paper): every cell that passes is a keypoint
  int orientation_bins = 36;
  template <typename Field>
  void fields(Field&& field) {
    field("window_scales.fine", window_scales[0], 3, 63);
    field("window_scales.middle", window_scales[1], 3, 63);
    field("window_scales.coarse", window_scales[2], 3, 63);
    field("percentile", percentile, 0, 100);
    field("descriptor_size", descriptor_size, 3, 63);
    field("min_tsd_m", min_tsd_m, 0, 1e5);
    field("suppression_radius", suppression_radius, 0, 50);
    field("orientation_bins", orientation_bins, 4, 360);
  }
};

// Why `descriptor_size` cannot make a descriptor, or nullopt: the descriptor is centred on its
// keypoint, so an even side (no centre) cannot.
std::optional<std::string> descriptor_size_fault(int descriptor_size);

struct Keypoint {
  Eigen::Vector3d position;  // submap frame (x, y, z down), z from the grid
  double tsd_m = 0;          // at the finest scale
  double orientation_rad = 0;  // dominant gradient direction, grid frame
  Eigen::VectorXf descriptor;  // d*d elevations, rotated to the orientation, minus their mean
};

// TSD of `grid` over square windows of `window` cells (valid cells only), computed with box
// filters; 0 where the window holds fewer than half its cells.
cv::Mat terrain_standard_deviation(const TerrainGrid& grid, int window);

std::vector<Keypoint> detect_keypoints(const TerrainGrid& grid, const KeypointConfig& config = {});

// Normalised cross-correlation of two descriptors (equation 10), in [-1, 1].
double descriptor_ncc(const Eigen::VectorXf& a, const Eigen::VectorXf& b);

// A descriptor as descriptor_ncc correlates it: its samples in double less their mean, and their
// sum of squares. Matching correlates a keypoint with every neighbour inside the gate, so it
// centres each descriptor once instead of once per neighbour; the result is the same number.
struct CentredDescriptor {
  Eigen::ArrayXd values;
  double sum_sq = 0;
};
CentredDescriptor centred(const Eigen::VectorXf& descriptor);
double descriptor_ncc(const CentredDescriptor& a, const CentredDescriptor& b);
// Mean squared difference of two descriptors, m^2: the match score of Algorithm 2. Given a
// `bound`, it stops summing once past it and returns some value at or above it: a matcher that
// only wants scores below its second best skips most of the sum (a tenth of a `lake` job).
double descriptor_mse(const Eigen::VectorXf& a, const Eigen::VectorXf& b,
                      double bound = std::numeric_limits<double>::infinity());

}  // namespace bathyslam
