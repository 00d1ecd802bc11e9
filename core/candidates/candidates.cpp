#include "core/candidates/candidates.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include <opencv2/imgproc.hpp>

#include "core/submaps/joined_surveys.h"

namespace bathyslam {
namespace {

constexpr double kCellM = 50.0;

// Grid cells (keyed) covered by a footprint's bounding box.
std::vector<int64_t> cells_of(const Footprint& f) {
  Eigen::Vector2d lo = f.corners[0], hi = f.corners[0];
  for (const auto& c : f.corners) {
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  std::vector<int64_t> cells;
  for (auto i = static_cast<int64_t>(std::floor(lo.x() / kCellM)); i <= std::floor(hi.x() / kCellM); ++i) {
    for (auto j = static_cast<int64_t>(std::floor(lo.y() / kCellM)); j <= std::floor(hi.y() / kCellM); ++j) {
      cells.push_back((i << 32) ^ (j & 0xffffffff));
    }
  }
  return cells;
}

}  // namespace

bool on_adjacent_lines(const SubmapSet& set, int a, int b, const CandidateConfig& config) {
  // Two surveys' lines are numbered on (join_surveys), not laid side by side.
  if (survey_of_submap(set, a) != survey_of_submap(set, b)) return false;
  const int la = set.submaps[a].line, lb = set.submaps[b].line;
  if (la < 0 || lb < 0 || la == lb || std::abs(la - lb) > config.k_adjacent_lines) return false;
  double d = std::fmod(std::abs(set.lines[la].course_deg - set.lines[lb].course_deg), 180.0);
  d = std::min(d, 180.0 - d);
  return d <= config.parallel_tolerance_deg;
}

Footprint footprint_of(const Submap& submap, const Eigen::Isometry3d& pose) {
  Eigen::AlignedBox2f box = submap.extent.isEmpty() ? extent_of(submap.points) : submap.extent;
  if (box.isEmpty()) box = Eigen::AlignedBox2f(Eigen::Vector2f::Zero(), Eigen::Vector2f::Zero());  // no points
  const Eigen::Vector2f lo = box.min(), hi = box.max();
  Footprint f;
  const Eigen::Vector2f local[4] = {{lo.x(), lo.y()}, {hi.x(), lo.y()}, {hi.x(), hi.y()}, {lo.x(), hi.y()}};
  for (int k = 0; k < 4; ++k) {
    f.corners[k] = (pose * Eigen::Vector3d(local[k].x(), local[k].y(), 0.0)).head<2>();
  }
  f.area_m2 = std::abs(static_cast<double>((hi - lo).prod()));
  return f;
}

FootprintOverlap footprint_overlap(const Footprint& a, const Footprint& b) {
  auto polygon = [](const Footprint& f) {
    std::vector<cv::Point2f> p;
    for (const auto& c : f.corners) p.emplace_back(static_cast<float>(c.x()), static_cast<float>(c.y()));
    if (cv::contourArea(p, true) < 0) std::reverse(p.begin(), p.end());
    return p;
  };
  std::vector<cv::Point2f> intersection;
  FootprintOverlap overlap;
  overlap.area_m2 = cv::intersectConvexConvex(polygon(a), polygon(b), intersection, true);
  for (const cv::Point2f& p : intersection) overlap.polygon.emplace_back(p.x, p.y);
  return overlap;
}

double overlap_area_m2(const Footprint& a, const Footprint& b) { return footprint_overlap(a, b).area_m2; }

namespace {

// Every pair (earlier, later) with the later in `later` that `wanted` admits and whose
// footprints overlap by at least `min_fraction` of the smaller one, found through a grid index
// over the footprints.
template <typename Wanted>
std::vector<CandidatePair> overlapping_pairs(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses,
                                             double min_fraction, LaterSubmaps later, Wanted&& wanted) {
  const int end = std::min(later.end, static_cast<int>(set.submaps.size()));
  std::vector<Footprint> footprints;
  std::unordered_map<int64_t, std::vector<int>> grid;
  for (int i = 0; i < end; ++i) {
    footprints.push_back(footprint_of(set.submaps[i], poses[i]));
    for (int64_t cell : cells_of(footprints.back())) grid[cell].push_back(i);
  }
  std::vector<CandidatePair> pairs;
  std::vector<int> near;
  for (int index = std::max(later.begin, 0); index < end; ++index) {
    const Submap& s = set.submaps[index];
    near.clear();
    for (int64_t cell : cells_of(footprints[s.index])) {
      const auto it = grid.find(cell);
      if (it == grid.end()) continue;
      for (int other : it->second) {
        if (other < s.index) near.push_back(other);
      }
    }
    std::sort(near.begin(), near.end());
    near.erase(std::unique(near.begin(), near.end()), near.end());
    for (int other : near) {
      if (!wanted(other, s.index)) continue;
      const double smaller = std::min(footprints[other].area_m2, footprints[s.index].area_m2);
      if (smaller <= 0) continue;
      const double fraction = overlap_area_m2(footprints[other], footprints[s.index]) / smaller;
      if (fraction >= min_fraction) pairs.push_back({other, s.index, fraction});
    }
  }
  return pairs;
}

}  // namespace

std::vector<CandidatePair> adjacent_line_candidates(const SubmapSet& set,
                                                    const std::vector<Eigen::Isometry3d>& poses,
                                                    const CandidateConfig& config, LaterSubmaps later) {
  return overlapping_pairs(set, poses, config.min_overlap_fraction, later,
                           [&](int a, int b) { return on_adjacent_lines(set, a, b, config); });
}

namespace {

// Keeps, of the pairs across two surveys, those each later submap overlaps most: at most
// `per_survey` with each earlier survey and `in_all` with all of them. Pairs within a survey all
// stay. `pairs` come grouped by their later submap.
std::vector<CandidatePair> best_across_surveys(const SubmapSet& set, std::vector<CandidatePair> pairs, int per_survey,
                                               int in_all) {
  if (set.survey_starts.empty()) return pairs;
  std::stable_sort(pairs.begin(), pairs.end(), [](const CandidatePair& a, const CandidatePair& b) {
    return a.source != b.source ? a.source < b.source : a.overlap_fraction > b.overlap_fraction;
  });
  std::vector<CandidatePair> kept;
  std::vector<int> taken(set.survey_starts.size() + 1, 0);  // the later submap's pairs, by survey
  int taken_in_all = 0;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const CandidatePair& p = pairs[k];
    if (k == 0 || p.source != pairs[k - 1].source) {
      std::fill(taken.begin(), taken.end(), 0);
      taken_in_all = 0;
    }
    const int survey = survey_of_submap(set, p.target);
    if (survey == survey_of_submap(set, p.source)) {
      kept.push_back(p);
    } else if (taken[survey] < per_survey && taken_in_all < in_all) {
      ++taken[survey];
      ++taken_in_all;
      kept.push_back(p);
    }
  }
  return kept;
}

}  // namespace

std::vector<CandidatePair> loop_candidates(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses,
                                           const CandidateConfig& config, LaterSubmaps later) {
  auto pairs = overlapping_pairs(set, poses, config.min_overlap_fraction, later, [&](int a, int b) {
    const bool apart = std::abs(a - b) >= config.loop_min_submap_gap || survey_of_submap(set, a) != survey_of_submap(set, b);
    return apart && !on_adjacent_lines(set, a, b, config);
  });
  return best_across_surveys(set, std::move(pairs), config.max_pairs_per_other_survey, config.max_pairs_across_surveys);
}

}  // namespace bathyslam
