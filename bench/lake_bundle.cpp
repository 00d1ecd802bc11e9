#include "bench/lake_bundle.h"

#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "core/io/bundle.h"
#include "core/sim/simulator.h"

namespace bathyslam::bench {

std::filesystem::path lake_bundle(int& argc, char** argv) {
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--bundle") == 0) {
      const std::filesystem::path bundle = argv[i + 1];
      for (int j = i; j + 2 <= argc; ++j) argv[j] = argv[j + 2];
      argc -= 2;
      return bundle;
    }
  }
  const std::filesystem::path bundle = std::filesystem::temp_directory_path() / "bathyslam_bench_lake";
  if (!std::filesystem::exists(bundle / kPingsFile)) {
    std::fprintf(stderr, "simulating lake (seed 1) into %s ...\n", bundle.c_str());
    sim::SimulationConfig config;
    config.scenario = sim::Scenario::kLake;
    write_bundle(sim::simulate(config).survey, bundle);
  }
  return bundle;
}

std::vector<Eigen::Isometry3d> reference_poses(const SubmapSet& submaps) {
  std::vector<Eigen::Isometry3d> truth;
  for (const Submap& s : submaps.submaps) {
    if (!s.reference_pose) throw std::runtime_error("the bundle has no reference_nav.csv: no truth to compare with");
    truth.push_back(*s.reference_pose);
  }
  return truth;
}

}  // namespace bathyslam::bench
