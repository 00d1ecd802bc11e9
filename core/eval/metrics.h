#pragma once
// eval: the quality report's numbers (docs/design.md, "Evaluation").
#include <functional>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "core/submaps/submap.h"

namespace bathyslam {

struct ErrorStats {
  double rmse = 0, mean = 0, std = 0, p50 = 0, p95 = 0, p99 = 0, max = 0;
  std::size_t count = 0;
};
ErrorStats error_stats(std::vector<double> errors);

struct Histogram {
  double bin_width = 0;
  std::vector<std::size_t> counts;  // the last bin also holds everything beyond it
};

struct ConsistencyConfig {
  double cell_m = 1.0;
  int min_soundings = 3;  // per line and cell
  double histogram_bin_m = 0.02;
  int histogram_bins = 100;
  template <typename Field>
  void fields(Field&& field) {
    field("cell_m", cell_m, 0.05, 1e5);
    field("min_soundings", min_soundings, 1, 1000);
    field("histogram_bin_m", histogram_bin_m, 0.001, 1e5);
    field("histogram_bins", histogram_bins, 1, 100000);
  }
};

struct ConsistencyReport {
  ErrorStats stats;
  Histogram histogram;
  // The p99's own uncertainty over the cells: the distribution-free one-sided 99 % upper
  // confidence bound of the 0.99 quantile, the order statistic at rank n·0.99 + 2.33·√(n·0.99·0.01)
  // (the binomial's normal approximation). Another sample of this seabed's cells could give a p99
  // this high with nothing changed.
  double p99_upper = 0;
};

// The value at quantile `p` of sorted `values` (the floor rank of p·(n − 1)), and the one-sided
// upper confidence bound of that quantile at `z` standard deviations of its rank.
double quantile_upper_bound(const std::vector<double>& sorted, double p, double z);

// The side of a square as large as the median submap's horizontal extent (0 for none): a
// submap's soundings move together with its pose, so its cells' errors are not independent.
double median_submap_side_m(const SubmapSet& set);

// The one-sided 99 % upper confidence bound of the consistency p99 (consistency_error) when its
// cells are not independent samples: the cells grouped into squares of `block_m`, the squares
// drawn with replacement `replicates` times (a block bootstrap, deterministic for one survey),
// the 99th percentile of the drawn p99s. Cells within a submap's extent share its pose error, so
// the distribution-free bound of ConsistencyReport::p99_upper, which counts every cell as its own
// sample, is far too tight for a whole map's tail.
double p99_upper_by_blocks(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses,
                           const ConsistencyConfig& config, double block_m, int replicates = 200);

// Roman & Singh consistency: per cell seen by two or more lines, the largest difference between
// the lines' mean elevations there. Submaps off the lines (turns) do not take part.
ConsistencyReport consistency_error(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses,
                                    const ConsistencyConfig& config = {});

// Several surveys of one site (SubmapSet::survey_starts): the same within each survey's lines,
// and across surveys, per cell seen by two of them, the largest difference between a line of one
// and a line of the other (every pair of surveys counted apart). A seabed that changed between the
// surveys shows in `across` too.
struct SiteConsistency {
  ConsistencyReport within, across;
};
// `changed` (map frame x, y): cells where the seabed changed between the surveys, left out of
// `across` (a change is not a disagreement of the registration).
SiteConsistency site_consistency(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses,
                                 const ConsistencyConfig& config = {},
                                 const std::function<bool(const Eigen::Vector2d&)>& changed = {});

// Horizontal distance of each submap pose from its reference pose (the first pose is shared).
std::vector<double> trajectory_errors(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses);

// The same after the best rigid 2D alignment (a turn about the vertical and a shift, Umeyama
// without scale) of the poses onto the reference: the absolute trajectory error that published
// bathymetric SLAM results report. A relative method cannot observe a rotation of the whole
// survey (a heading bias shared by every line); this error does not charge it for one.
std::vector<double> aligned_trajectory_errors(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses);

// How far a measured relative pose (`to` in the frame of `from`) is from the one the reference
// poses give; nullopt without a reference.
struct RelativePoseError {
  double translation_m = 0;  // full 3D
  double horizontal_m = 0;   // in the `from` frame's x-y plane
  double yaw_deg = 0;        // signed
};
std::optional<RelativePoseError> relative_pose_error(const SubmapSet& set, int from, int to,
                                                     const Eigen::Isometry3d& measured);

// How many standard deviations of its own information a graph edge is off the reference, where
// the graph compares it: horizontally at its anchor (`to`'s frame) in `from`'s frame, and in yaw.
// An edge many sigmas off is confidently wrong: it pulls the map with weight it has not earned.
struct EdgeErrorSigmas {
  double horizontal = 0;  // sqrt(e_xy' * information_xy * e_xy)
  double yaw = 0;         // |e_yaw| * sqrt(information_yaw)
  // x, y and yaw together, with their cross terms: sqrt(r' Ω r), r the graph's residual at the
  // truth (translation truth − measured at the anchor, rotation measured − truth, as
  // relative_pose_error.h takes them). Information shaped by a registration's Hessian couples
  // translation and yaw (a patch pins a rotation about a point of its own), which the two
  // figures above, each conditional on the other, cannot tell.
  double joint = 0;
  Eigen::Vector2d at_anchor_m = Eigen::Vector2d::Zero();  // the horizontal error itself (measured − truth)
};
std::optional<EdgeErrorSigmas> edge_error_sigmas(const SubmapSet& set, int from, int to, const Eigen::Isometry3d& measured,
                                                 const Eigen::Vector3d& anchor,
                                                 const Eigen::Matrix<double, 6, 6>& information);

}  // namespace bathyslam
