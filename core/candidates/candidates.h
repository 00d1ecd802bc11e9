#pragma once
// candidates: pairs of submaps worth registering, from their dead-reckoning footprints.
#include <array>
#include <limits>
#include <vector>

#include <Eigen/Geometry>

#include "core/submaps/submap.h"

namespace bathyslam {

// A submap's footprint on the seafloor: the rectangle its soundings span in the submap frame,
// placed in the map frame (x, y) by a pose.
struct Footprint {
  std::array<Eigen::Vector2d, 4> corners;
  double area_m2 = 0;
};

Footprint footprint_of(const Submap& submap, const Eigen::Isometry3d& pose);

// The intersection of two footprints: its area and its corners, counter-clockwise (none when the
// footprints do not meet).
struct FootprintOverlap {
  double area_m2 = 0;
  std::vector<Eigen::Vector2d> polygon;
};
FootprintOverlap footprint_overlap(const Footprint& a, const Footprint& b);

// Area of the intersection of two footprints.
double overlap_area_m2(const Footprint& a, const Footprint& b);

struct CandidateConfig {
  int k_adjacent_lines = 3;            // Table 1 (a)
  double parallel_tolerance_deg = 20;  // lines within this of parallel or antiparallel
  // Intersection over the smaller footprint. Table 1's "overlap coverage 0.9" cannot hold between
  // lawnmower lines that share only ~40 % of a swath; see docs/slam-core.md, "Departures from Table 1".
  double min_overlap_fraction = 0.1;
  // Loop candidates: submaps this many apart in time or more (nearer ones are odometry's).
  int loop_min_submap_gap = 5;
  // Pairs across two surveys of one site: a later submap registers with at most this many of each
  // earlier survey's submaps, those it overlaps most. Every overlapping pair made a job of N
  // surveys cost about N² single ones (docs/sites.md). 0: none, each survey registered alone and
  // placed by its start fix (the surveys "processed apart" to compare with).
  int max_pairs_per_other_survey = 2;
  // ... and at most this many across all earlier surveys, those it overlaps most: a job of N
  // surveys then costs about N single ones, not N².
  int max_pairs_across_surveys = 4;
  template <typename Field>
  void fields(Field&& field) {
    field("k_adjacent_lines", k_adjacent_lines, 1, 100);
    field("parallel_tolerance_deg", parallel_tolerance_deg, 0, 90);
    field("min_overlap_fraction", min_overlap_fraction, 0, 1);
    field("loop_min_submap_gap", loop_min_submap_gap, 1, 100000);
    field("max_pairs_per_other_survey", max_pairs_per_other_survey, 0, 100000);
    field("max_pairs_across_surveys", max_pairs_across_surveys, 0, 100000);
  }
};

// Whether submaps `a` and `b` lie on distinct survey lines of one survey at most K apart that run
// parallel or antiparallel (the pairs the `gicp` configuration registers).
bool on_adjacent_lines(const SubmapSet& set, int a, int b, const CandidateConfig& config);

struct CandidatePair {
  int target = 0;  // earlier submap
  int source = 0;  // later submap
  double overlap_fraction = 0;
};

// The submaps a search takes as the later of a pair: all, or one batch's [begin, end). A
// batch's search then costs the batch and not the survey so far (`large`: 316 batches).
struct LaterSubmaps {
  int begin = 0;
  int end = std::numeric_limits<int>::max();
};

// Pairs on K-adjacent parallel lines whose footprints (at `poses`) overlap enough. A grid index
// over the footprints keeps this near-linear in the number of submaps.
std::vector<CandidatePair> adjacent_line_candidates(const SubmapSet& set,
                                                    const std::vector<Eigen::Isometry3d>& poses,
                                                    const CandidateConfig& config = {}, LaterSubmaps later = {});

// Loop-closure candidates: pairs whose footprints (at `poses`) overlap enough but that are not
// on K-adjacent parallel lines (check lines crossing the lawnmower, revisits, turns), and are
// far enough apart in time; and pairs of two surveys of one site (join_surveys): for each later
// submap those it overlaps most, within the caps per earlier survey and in all.
std::vector<CandidatePair> loop_candidates(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses,
                                           const CandidateConfig& config = {}, LaterSubmaps later = {});

}  // namespace bathyslam
