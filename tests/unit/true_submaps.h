#pragma once
// Submaps of a simulated `small` survey built from its true navigation: footprints lie where the
// soundings really are, and any pair's true relative pose is the one their poses give.
#include <algorithm>
#include <cmath>
#include <optional>

#include "core/candidates/candidates.h"
#include "core/sim/simulator.h"
#include "core/submaps/submap.h"

namespace bathyslam {

inline SubmapSet true_small_submaps(uint64_t seed) {
  sim::SimulationConfig config;
  config.seed = seed;
  Survey survey = sim::simulate(config).survey;
  survey.nav = *survey.reference_nav;
  return build_submaps(survey);
}

inline std::vector<Eigen::Isometry3d> poses_of(const SubmapSet& set) {
  std::vector<Eigen::Isometry3d> poses;
  for (const Submap& s : set.submaps) poses.push_back(s.dr_pose);
  return poses;
}

// The adjacent-line pair (at the submaps' own poses) overlapping by more than 30 % on the
// roughest ground (the larger relief of its flatter submap): GICP cannot see a horizontal offset
// on a flat bottom, so registration tests that check one take this pair. None if no pair
// overlaps that much.
inline std::optional<CandidatePair> roughest_adjacent_pair(const SubmapSet& set) {
  auto relief = [&](int i) {
    double lo = INFINITY, hi = -INFINITY;
    for (const Eigen::Vector3f& p : set.submaps[i].points) {
      lo = std::min<double>(lo, p.z());
      hi = std::max<double>(hi, p.z());
    }
    return hi - lo;
  };
  std::optional<CandidatePair> pair;
  double best = -1;
  for (const CandidatePair& p : adjacent_line_candidates(set, poses_of(set))) {
    const double r = std::min(relief(p.target), relief(p.source));
    if (p.overlap_fraction > 0.3 && r > best) {
      best = r;
      pair = p;
    }
  }
  return pair;
}

}  // namespace bathyslam
