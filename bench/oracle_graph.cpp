// The trajectory error a perfect front end would leave: every candidate pair (K-adjacent and
// loop, found at the reference poses) gets an edge equal to its true relative pose, with the
// `mchs` best-quality information, and the graph is solved from dead reckoning as the pipeline
// solves it. Registrations relate submaps to each other only, so whatever drift the survey's
// geometry cannot see stays; this is the floor under any registration method's trajectory RMSE.
//   bench_oracle_graph BUNDLE [--no-loops] [--edges REPORT] [--observable [--identifiable]] [key=value ...]
// --observable: the achievable floor on this seabed (issue 31). Each pair's true edge carries only
// the information its overlap supports: the GICP cost's curvature at the truth, shaped and
// weighed as `mchs` weighs a registration's (quality_information with information_from_hessian),
// and the DR noise is the survey's own as `mchs` estimates it (navigation_noise.h), from these
// edges. Prints the trajectory RMSE (unaligned and aligned) and the map's consistency RMSE and p99,
// with dead reckoning's, and a last line `floor traj aligned cons p99` for scripts.
// --edges takes the pairs from a report.json instead: its accepted registrations only, at the
// truth, direct-path adjacent ones with depth, roll and pitch only, as `mchs` weighs them. This
// separates what the front end got wrong from what the terrain never offered.
// --identifiable (with --observable): what a method that judges each pair on its own overlap and
// dead reckoning can reach. The truth is probed as a registration's answer is (the terrain slid
// about it, register/uniqueness.h), and where another offset fits nearly as well and dead
// reckoning (at the survey's noise, estimated as above) does not rule it out, the pair keeps no
// more than `mchs`'s alias rule gives an answer there (resolve_alias): on a periodic seabed with
// drift beyond half its wavelength, the true alignment is one of several that the pair alone cannot
// tell apart. Only a joint choice over many pairs could do better.
// key=value: pipeline parameters, e.g. graph.dr_sigma_rotation_rad.yaw=0.005.
#include <cstdio>
#include <exception>
#include <string>

#include "bench/report_registrations.h"
#include "core/filter/voxel_filter.h"
#include "core/graph/loop_consistency.h"
#include "core/eval/metrics.h"
#include "core/io/bundle.h"
#include "core/pipeline/pipeline.h"
#include "core/pipeline/robust_backend.h"

using namespace bathyslam;

namespace {

// The edge the truth gives a pair, with the information its overlap supports there.
PoseGraphEdge observed_edge(const std::vector<Eigen::Isometry3d>& reference, const CandidatePair& p,
                            GicpCloudCache& prepared, const PipelineConfig& config) {
  const Eigen::Isometry3d truth = reference[p.target].inverse() * reference[p.source];
  const PairRegistration seen = observe_at(prepared.at(p.target), prepared.at(p.source), truth, config.registration.gicp,
                                           config.registration.crop_margin_m);
  PoseGraphEdge edge{p.target, p.source, truth, Information6::Zero(), true, seen.anchor};
  if (seen.hessian.correspondences == 0) return edge;
  const Eigen::Matrix3d level_from_target =
      level_from_body(Eigen::Quaterniond(reference[p.target].rotation())).toRotationMatrix();
  edge.information = quality_information(seen, config.quality, level_from_target);
  return edge;
}

// The pair's true edge after the alias rule, as if a direct registration had answered the truth.
PoseGraphEdge identifiable_edge(const PoseGraphEdge& observed, const TerrainGrid& target, const TerrainGrid& source,
                                const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses,
                                const PipelineConfig& config) {
  Constraint c;
  c.type = ConstraintType::kLoop;
  c.from = observed.from;
  c.to = observed.to;
  c.measured = observed.measured;
  c.anchor = observed.anchor;
  c.information = observed.information;
  c.path = RegistrationPath::kDirect;
  c.uniqueness = probe_uniqueness(target, source, observed.measured, config.registration.uniqueness);
  const Eigen::Matrix3d level_from_target = level_from_body(Eigen::Quaterniond(dr_poses[c.from].rotation())).toRotationMatrix();
  resolve_alias(c, dr, dr_poses, config.acceptance.min_distinctness, config.robustness.pcm.plausibility, level_from_target,
                alias_rule(config.quality));
  PoseGraphEdge edge = observed;
  edge.information = c.information;
  return edge;
}

int observable_floor(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& dr,
                     const std::vector<Eigen::Isometry3d>& reference, PipelineConfig config, bool loops_on,
                     bool identifiable) {
  config.quality.information_from_hessian = true;
  const auto filtered = [&](std::size_t i) -> Cloud::ConstPtr { return voxel_filter(set.submaps[i].points, config.voxel); };
  GicpCloudCache prepared(set.submaps.size(), filtered, config.registration.gicp);
  std::vector<CandidatePair> pairs = adjacent_line_candidates(set, reference, config.candidates);
  if (loops_on) {
    for (const CandidatePair& p : loop_candidates(set, reference, config.candidates)) pairs.push_back(p);
  }
  std::vector<PoseGraphEdge> registrations;
  for (const CandidatePair& p : pairs) registrations.push_back(observed_edge(reference, p, prepared, config));

  // The survey's own DR noise from these edges, as `mchs` estimates it from its registrations.
  const DrNoiseModel any(dr, config.graph);
  std::vector<DrInnovation> innovations;
  for (const PoseGraphEdge& e : registrations) {
    if (carries_horizontal_information(e.information)) innovations.push_back(dr_innovation(e, any, dr));
  }
  const NavigationNoiseEstimate noise = estimate_navigation_noise(dr, innovations, config.graph, config.navigation_noise);
  if (identifiable) {
    std::vector<TerrainGrid> grids;
    for (const Submap& s : set.submaps) grids.push_back(grid_terrain(s.points, config.grid));
    const DrNoiseModel model(dr, noise.graph);
    std::size_t kept = 0;
    for (PoseGraphEdge& e : registrations) {
      if (!carries_horizontal_information(e.information)) continue;
      e = identifiable_edge(e, grids[e.from], grids[e.to], model, dr, config);
      kept += carries_horizontal_information(e.information);
    }
    std::printf("%zu of %zu pairs with horizontal information keep it where dead reckoning rules out every alias\n", kept,
                innovations.size());
  }
  std::vector<PoseGraphEdge> edges = odometry_edges(
      dr, information_from_sigmas(noise.graph.dr_sigma_translation_m, noise.graph.dr_sigma_rotation_rad));
  edges.insert(edges.end(), registrations.begin(), registrations.end());
  const GraphSolution solution = optimize_pose_graph(dr, edges, noise.graph);

  const ErrorStats traj_dr = error_stats(trajectory_errors(set, dr)), traj = error_stats(trajectory_errors(set, solution.poses));
  const ErrorStats aligned_dr = error_stats(aligned_trajectory_errors(set, dr));
  const ErrorStats aligned = error_stats(aligned_trajectory_errors(set, solution.poses));
  const ErrorStats cons_dr = consistency_error(set, dr, config.consistency).stats;
  const ErrorStats cons = consistency_error(set, solution.poses, config.consistency).stats;
  // The map at the true submap poses: what no registration can improve on, only overfit.
  const ErrorStats cons_true = consistency_error(set, reference, config.consistency).stats;
  std::printf("%zu submaps, %zu pairs at the truth with the information their overlap supports; DR noise %.3f m, %.5f rad "
              "per step from %d of them\n",
              dr.size(), registrations.size(), noise.graph.dr_sigma_translation_m.x(), noise.graph.dr_sigma_rotation_rad.z(),
              noise.innovations);
  std::printf("trajectory RMSE: dead reckoning %.2f m, floor %.2f m; aligned %.2f m, floor %.2f m\n", traj_dr.rmse, traj.rmse,
              aligned_dr.rmse, aligned.rmse);
  std::printf("consistency RMSE: dead reckoning %.3f m, floor %.3f m; p99 %.3f m, floor %.3f m\n", cons_dr.rmse, cons.rmse,
              cons_dr.p99, cons.p99);
  std::printf("consistency RMSE at the true poses %.3f m, p99 %.3f m\n", cons_true.rmse, cons_true.p99);
  std::printf("floor %.4f %.4f %.5f %.5f\n", traj.rmse, aligned.rmse, cons.rmse, cons.p99);
  return 0;
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s BUNDLE [--no-loops] [--edges REPORT] [key=value ...]\n", argv[0]);
    return 2;
  }
  PipelineConfig config;
  bool loops_on = true, observable = false;
  bool identifiable = false;
  std::string report;
  for (int i = 2; i < argc; ++i) {
    const std::string kv = argv[i];
    if (kv == "--no-loops") { loops_on = false; continue; }
    if (kv == "--observable") { observable = true; continue; }
    if (kv == "--identifiable") { observable = identifiable = true; continue; }
    if (kv == "--edges" && i + 1 < argc) { report = argv[++i]; continue; }
    set_parameter(config, kv);
  }
  const Survey survey = load_bundle(argv[1]);
  const SubmapSet set = build_submaps(survey, config.submaps);
  config = scaled_to_footprint(config, footprint_scale(set.footprint, config));  // as the pipeline's lengths
  std::vector<Eigen::Isometry3d> dr, reference;
  for (const Submap& s : set.submaps) {
    if (!s.reference_pose) throw std::runtime_error(std::string(argv[1]) + ": no reference_nav.csv");
    dr.push_back(s.dr_pose);
    reference.push_back(*s.reference_pose);
  }
  std::vector<PoseGraphEdge> edges = odometry_edges(
      dr, information_from_sigmas(config.graph.dr_sigma_translation_m, config.graph.dr_sigma_rotation_rad));
  const Information6 best = information_from_sigmas(config.quality.best_sigma_translation_m,
                                                    config.quality.best_sigma_rotation_rad);
  Information6 depth_only = best;
  for (int k : {0, 1, 5}) depth_only(k, k) = 0;
  std::size_t adjacent = 0, loops = 0;
  auto add = [&](const std::vector<CandidatePair>& pairs, const Information6& information, std::size_t& count) {
    for (const CandidatePair& p : pairs) {
      edges.push_back({p.target, p.source, reference[p.target].inverse() * reference[p.source], information, true});
      ++count;
    }
  };
  if (observable) return observable_floor(set, dr, reference, config, loops_on, identifiable);
  if (report.empty()) {
    add(adjacent_line_candidates(set, reference, config.candidates), best, adjacent);
    if (loops_on) add(loop_candidates(set, reference, config.candidates), best, loops);
  } else {
    for (const bench::ReportRegistration& r : bench::read_report(report, static_cast<int>(dr.size())).registrations) {
      if (!r.accepted) continue;
      const bool loop = r.type == "loop";
      add({CandidatePair{r.from, r.to}}, loop || r.path == "feature-aided" ? best : depth_only, loop ? loops : adjacent);
    }
  }
  const GraphSolution solution = optimize_pose_graph(dr, edges, config.graph);
  const ErrorStats dr_stats = error_stats(trajectory_errors(set, dr));
  const ErrorStats oracle = error_stats(trajectory_errors(set, solution.poses));
  std::printf("%s: %zu submaps, %zu adjacent + %zu loop edges at the truth\n", argv[1], dr.size(), adjacent, loops);
  std::printf("trajectory RMSE: dead reckoning %.2f m, perfect front end %.2f m (%.1f %% below)\n", dr_stats.rmse,
              oracle.rmse, 100.0 * (1.0 - oracle.rmse / dr_stats.rmse));
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_oracle_graph: %s\n", e.what());
  return 1;
}
