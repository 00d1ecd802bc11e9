#pragma once
// The benchmarks' input: a bundle given as `--bundle DIR` (removed from argv), or the `lake`
// survey of seed 1 simulated once into a temporary folder and reused by later runs.
#include <filesystem>
#include <vector>

#include "core/submaps/submap.h"

namespace bathyslam::bench {

std::filesystem::path lake_bundle(int& argc, char** argv);

// The submaps' reference poses, the truth the benchmarks compare with; throws when the bundle
// had no reference navigation.
std::vector<Eigen::Isometry3d> reference_poses(const SubmapSet& submaps);

}  // namespace bathyslam::bench
