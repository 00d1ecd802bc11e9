// The trajectory error a perfect front end would leave: every candidate pair (K-adjacent and
// loop, found at the reference poses) gets an edge equal to its true relative pose, with the
// `mchs` best-quality information, and the graph is solved from dead reckoning as the pipeline
// solves it. Registrations relate submaps to each other only, so whatever drift the survey's
// geometry cannot see stays; this is the floor under any registration method's trajectory RMSE.
//   bench_oracle_graph BUNDLE [--no-loops] [--edges REPORT] [key=value ...]
// --edges takes the pairs from a report.json instead: its accepted registrations only, at the
// truth, direct-path adjacent ones with depth, roll and pitch only, as `mchs` weighs them. This
// separates what the front end got wrong from what the terrain never offered.
// key=value: pipeline parameters, e.g. graph.dr_sigma_rotation_rad.yaw=0.005.
#include <cstdio>
#include <exception>
#include <string>

#include "bench/report_registrations.h"
#include "core/eval/metrics.h"
#include "core/io/bundle.h"
#include "core/pipeline/pipeline.h"

using namespace bathyslam;

int main(int argc, char** argv) try {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s BUNDLE [--no-loops] [--edges REPORT] [key=value ...]\n", argv[0]);
    return 2;
  }
  PipelineConfig config;
  bool loops_on = true;
  std::string report;
  for (int i = 2; i < argc; ++i) {
    const std::string kv = argv[i];
    if (kv == "--no-loops") { loops_on = false; continue; }
    if (kv == "--edges" && i + 1 < argc) { report = argv[++i]; continue; }
    set_parameter(config, kv);
  }
  const Survey survey = load_bundle(argv[1]);
  const SubmapSet set = build_submaps(survey, config.submaps);
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
