#pragma once
// The benchmarks' input: a bundle given as `--bundle DIR` (removed from argv), or the `lake`
// survey of seed 1 simulated once into a temporary folder and reused by later runs.
#include <filesystem>

namespace bathyslam::bench {

std::filesystem::path lake_bundle(int& argc, char** argv);

}  // namespace bathyslam::bench
