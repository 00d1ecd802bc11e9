// Re-solves a run's pose graph from its report, without registering again: the accepted
// registrations' measured poses become edges, weighed as the run weighed them or, with
// --uniform, all with the `gicp` sigmas given. Registration is most of a job's time and does not
// depend on the weights, so this is how weights are compared across seeds in seconds.
//   bench_regraph BUNDLE REPORT [--uniform] [key=value ...]
// key=value: pipeline parameters over the run's own (report.json "parameters"), e.g.
// uniform_information.sigma_translation_m.x=2 graph.huber_delta=0.5.
#include <chrono>
#include <cstdio>
#include <exception>
#include <string>

#include "bench/report_registrations.h"
#include "core/eval/metrics.h"
#include "core/io/bundle.h"

using namespace bathyslam;

int main(int argc, char** argv) try {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s BUNDLE REPORT [--uniform] [key=value ...]\n", argv[0]);
    return 2;
  }
  const Survey survey = load_bundle(argv[1]);
  const SubmapSet set = build_submaps(survey, PipelineConfig{}.submaps);
  bench::Report report = bench::read_report(argv[2], static_cast<int>(set.submaps.size()));
  PipelineConfig& config = report.config;
  bool uniform = false;
  for (int i = 3; i < argc; ++i) {
    const std::string kv = argv[i];
    if (kv == "--uniform") { uniform = true; continue; }
    set_parameter(config, kv);
  }
  if (config.submaps.pings_per_submap != PipelineConfig{}.submaps.pings_per_submap) {
    throw std::runtime_error(std::string(argv[2]) + ": made with submaps.pings_per_submap=" +
                             std::to_string(config.submaps.pings_per_submap) + ", which this tool does not rebuild");
  }
  std::vector<Eigen::Isometry3d> dr;
  for (const Submap& s : set.submaps) dr.push_back(s.dr_pose);
  std::vector<PoseGraphEdge> edges = odometry_edges(
      dr, information_from_sigmas(config.graph.dr_sigma_translation_m, config.graph.dr_sigma_rotation_rad));
  const Information6 uniform_information =
      information_from_sigmas(config.uniform_information.sigma_translation_m,
                              config.uniform_information.sigma_rotation_rad);
  std::size_t used = 0;
  for (const bench::ReportRegistration& r : report.registrations) {
    if (!r.accepted) continue;
    if (!r.has_measured) throw std::runtime_error(std::string(argv[2]) + ": has no measured poses (an older report)");
    edges.push_back({r.from, r.to, r.measured, uniform ? uniform_information : r.information, true, r.anchor});
    ++used;
  }
  const auto start = std::chrono::steady_clock::now();
  const GraphSolution solution = optimize_pose_graph(dr, edges, config.graph);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const ErrorStats t0 = error_stats(trajectory_errors(set, dr));
  const ErrorStats t = error_stats(trajectory_errors(set, solution.poses));
  const ConsistencyReport c0 = consistency_error(set, dr, config.consistency);
  const ConsistencyReport c = consistency_error(set, solution.poses, config.consistency);
  std::printf("%s: %zu registration edges%s, solved from dead reckoning in %.3f s (%d iterations)\n", argv[2], used,
              uniform ? " at uniform information" : "", seconds, solution.iterations);
  std::printf("trajectory RMSE %.2f m (dead reckoning %.2f m); consistency RMSE %.3f m (dead reckoning %.3f m)\n",
              t.rmse, t0.rmse, c.stats.rmse, c0.stats.rmse);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_regraph: %s\n", e.what());
  return 1;
}
