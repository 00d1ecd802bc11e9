// Where our GICP lands from each candidate pair's true pose and from starts shifted about it, and
// the direction the cost's Hessian at the truth observes least: on a seabed whose cost is a
// valley (sand waves), the answers slide along it, and the Hessian says where it runs.
//
//   bench_gicp_basin BUNDLE [SHIFT_M=2]
//
// One line per candidate pair (at the reference poses): the Hessian's weakest horizontal
// direction in degrees from the target frame's x, conditional on the other four degrees of
// freedom ("conditional") and with them marginalised ("marginal"); then the landing's error at
// the overlap's centroid (target frame, m) from the truth and from starts SHIFT_M along +x, -x,
// +y and -y. docs/slam-every-seabed.md, "Information taken out of a direction".
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "bench/lake_bundle.h"
#include "core/io/bundle.h"
#include "core/pipeline/pipeline.h"
#include "core/register/coarse_to_fine.h"

namespace {

using namespace bathyslam;

// Of the direction an information block observes least, degrees in [0, 180).
double weakest_direction_deg(const Eigen::Matrix2d& information) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(information);
  const Eigen::Vector2d v = eigen.eigenvectors().col(0);
  const double deg = std::atan2(v.y(), v.x()) * 180 / M_PI;
  return deg < 0 ? deg + 180 : deg;
}

void print_pair(GicpCloudCache& prepared, const CandidatePair& pair, const std::vector<Eigen::Isometry3d>& truth,
                const PipelineConfig& config, double shift_m) {
  const PairClouds clouds = prepared_pair(prepared, pair.target, pair.source);
  const Eigen::Isometry3d true_pose = truth[pair.target].inverse() * truth[pair.source];
  const GicpConfig& gicp = config.registration.gicp;
  const double crop = config.registration.crop_margin_m;

  const PairRegistration at_truth =
      observe_at(*clouds.prepared_target, *clouds.prepared_source, true_pose, gicp, crop);
  const Eigen::Matrix<double, 6, 6> observed = at_truth.hessian.hessian - at_truth.hessian.regularisation;
  const Eigen::Matrix<double, 6, 6> covariance = (observed + 1e-9 * Eigen::Matrix<double, 6, 6>::Identity()).inverse();
  std::printf("%3d-%3d conditional %4.0f marginal %4.0f |", pair.target, pair.source,
              weakest_direction_deg(observed.topLeftCorner<2, 2>()),
              weakest_direction_deg(covariance.topLeftCorner<2, 2>().inverse()));

  for (const Eigen::Vector2d& d : {Eigen::Vector2d(0, 0), Eigen::Vector2d(shift_m, 0), Eigen::Vector2d(-shift_m, 0),
                                   Eigen::Vector2d(0, shift_m), Eigen::Vector2d(0, -shift_m)}) {
    Eigen::Isometry3d start = true_pose;
    start.pretranslate(Eigen::Vector3d(d.x(), d.y(), 0));
    const PairRegistration landed = register_direct(clouds, start, gicp, crop);
    const Eigen::Vector3d error = landed.registration.source_to_target * landed.anchor - true_pose * landed.anchor;
    std::printf(" (%+5.2f %+5.2f)", error.x(), error.y());
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_gicp_basin BUNDLE [SHIFT_M=2]\n");
    return 2;
  }
  const Survey survey = load_bundle(argv[1]);
  const double shift_m = argc > 2 ? std::atof(argv[2]) : 2.0;
  PipelineConfig config;
  config.configuration = Configuration::kMchs;
  const SubmapSet set = build_submaps(survey, config.submaps);
  const std::vector<Eigen::Isometry3d> truth = bench::reference_poses(set);
  std::vector<CandidatePair> pairs = adjacent_line_candidates(set, truth, config.candidates);
  for (const CandidatePair& p : loop_candidates(set, truth, config.candidates)) pairs.push_back(p);
  // Each submap filtered and prepared once, on its first pair, as the pipeline does.
  GicpCloudCache prepared(
      set.submaps.size(), [&](std::size_t i) -> Cloud::ConstPtr { return voxel_filter(set.submaps[i].points, config.voxel); },
      config.registration.gicp);
  for (const CandidatePair& p : pairs) print_pair(prepared, p, truth, config, shift_m);
  return 0;
}
