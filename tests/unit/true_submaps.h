#pragma once
// Submaps of a simulated `small` survey built from its true navigation: footprints lie where the
// soundings really are, and any pair's true relative pose is the one their poses give.
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

}  // namespace bathyslam
