#include "core/pipeline/safety_net.h"

#include <algorithm>
#include <cmath>

#include "core/types/format.h"

namespace bathyslam {
namespace {

// How hard an edge pulls against a solution, in sigmas of its own information on x, y and yaw.
double horizontal_pull_sigma(const PoseGraphEdge& edge, const std::vector<Eigen::Isometry3d>& poses) {
  const Eigen::Matrix<double, 6, 1> error = edge_error(edge, poses[edge.from], poses[edge.to]);
  const Eigen::Vector3d e(error(0), error(1), error(5));
  return std::sqrt(std::max(0.0, e.dot(xy_yaw_block(edge.information) * e)));
}

std::string describe(const Constraint& c) {
  return to_string(c.type) + " " + std::to_string(c.from) + "->" + std::to_string(c.to) + " (" + (c.path ? to_string(*c.path) : "odometry") + ")";
}

// How high dead reckoning's p99 could be by the sampling of its cells alone (publish_rule).
// The block bootstrap re-reads the map, so it runs only where the cheaper bound would refuse.
double dr_p99_bound(const ConsistencyReport& dr, double solved_p99, const SubmapSet& submaps,
                    const std::vector<Eigen::Isometry3d>& dr_poses, const PipelineConfig& config) {
  const int rule = config.robustness.publish_rule;
  if (rule == 0) return dr.stats.p99;
  const double cells = std::max(dr.stats.p99, dr.p99_upper);
  if (rule == 1 || solved_p99 <= cells) return cells;
  const double block_m = median_submap_side_m(submaps);
  if (block_m <= 0) return cells;
  return std::max(cells, p99_upper_by_blocks(submaps, dr_poses, config.consistency, block_m));
}

std::string pass_after_drops(std::size_t dropped) {
  return format("pass after dropping %.0f registrations", static_cast<double>(dropped));
}

}  // namespace

Publication solve_with_safety_net(const std::vector<Eigen::Isometry3d>& dr_poses, const std::vector<int>& line_of_node,
                                  std::vector<Constraint>& constraints, const GraphConfig& graph,
                                  const PipelineConfig::Robustness& robustness) {
  Publication published;
  SafetyNet& net = published.safety_net;
  net.ran = true;
  for (int round = 0;; ++round) {
    std::vector<PoseGraphEdge> edges;
    std::vector<std::size_t> owner;
    for (std::size_t k = 0; k < constraints.size(); ++k) {
      if (!constraints[k].in_graph()) continue;
      edges.push_back(graph_edge(constraints[k]));
      owner.push_back(k);
    }
    published.graph = optimize_pose_graph(dr_poses, edges, graph);
    net.check = check_graph(published.graph.poses, edges, line_of_node, robustness.line_check);
    int hardest = -1;
    double hardest_sigma = 0;
    for (std::size_t e = 0; e < edges.size(); ++e) {
      if (!edges[e].robust) continue;
      const double sigma = horizontal_pull_sigma(edges[e], published.graph.poses);
      if (sigma > hardest_sigma) hardest_sigma = sigma, hardest = static_cast<int>(e);
    }
    const bool pulls = hardest_sigma > robustness.max_pull_sigma;
    if (net.check.pass && !pulls) {
      net.verdict = net.dropped.empty()
                        ? "pass: every line within dead reckoning's noise, no registration pulling beyond " +
                              format("%.0f sigma", robustness.max_pull_sigma)
                        : pass_after_drops(net.dropped.size());
      return published;
    }
    if (hardest < 0 || round >= robustness.max_drops) {
      publish_dead_reckoning(
          published, dr_poses, constraints,
          format("FAILED after dropping %.0f registrations (%s): published dead reckoning instead",
                 static_cast<double>(net.dropped.size()),
                 net.check.pass ? "registrations still pulling against the solution" : "lines bent beyond their noise"));
      return published;
    }
    Constraint& worst = constraints[owner[hardest]];
    worst.exclusion = {RejectionKind::kSafetyNet, format("pulled %.1f sigma against the solution", hardest_sigma) +
                                                      (net.check.pass ? "" : ", lines bent beyond their noise")};
    net.dropped.push_back(describe(worst) + ": " + worst.exclusion.text());
  }
}

void count_earlier_drops(SafetyNet& net, const SafetyNet& earlier) {
  net.dropped.insert(net.dropped.begin(), earlier.dropped.begin(), earlier.dropped.end());
  if (net.pass && !net.dropped.empty()) net.verdict = pass_after_drops(net.dropped.size());
}

void publish_dead_reckoning(Publication& published, const std::vector<Eigen::Isometry3d>& dr_poses,
                            std::vector<Constraint>& constraints, const std::string& verdict) {
  published.safety_net.pass = false;
  published.safety_net.fell_back = true;
  published.safety_net.verdict = verdict;
  published.graph.poses = dr_poses;
  for (Constraint& c : constraints) {
    if (!from_navigation(c.type) && c.in_graph()) c.exclusion = {RejectionKind::kSafetyNet, "dead reckoning published instead"};
  }
}

std::optional<std::string> less_consistent_than_dead_reckoning(const ConsistencyReport& solved_map,
                                                               const ConsistencyReport& dr_map, const SubmapSet& submaps,
                                                               const std::vector<Eigen::Isometry3d>& dr_poses,
                                                               const PipelineConfig& config) {
  const ErrorStats &solved = solved_map.stats, &dr = dr_map.stats;
  const bool whole_map = config.robustness.publish_rule >= 1;
  const bool rmse_no_higher = solved.rmse <= dr.rmse;
  const double p99_bound = rmse_no_higher ? dr_p99_bound(dr_map, solved.p99, submaps, dr_poses, config) : dr.p99;
  if (rmse_no_higher && solved.p99 <= p99_bound) return std::nullopt;
  return format("FAILED: the solved map agrees with itself less than dead reckoning's (consistency RMSE %.3f m "
                "against %.3f m, p99 %.3f m against %.3f m%s): published dead reckoning instead",
                solved.rmse, dr.rmse, solved.p99, dr.p99,
                whole_map && rmse_no_higher ? format(", at most %.3f m within its sampling noise", p99_bound).c_str() : "");
}

bool fall_back_unless_more_consistent(Publication& published, ConsistencyReport& solved, const ConsistencyReport& dr,
                                      const SubmapSet& submaps, const std::vector<Eigen::Isometry3d>& dr_poses,
                                      std::vector<Constraint>& constraints, const PipelineConfig& config) {
  const auto why = less_consistent_than_dead_reckoning(solved, dr, submaps, dr_poses, config);
  if (!why) return false;
  publish_dead_reckoning(published, dr_poses, constraints, *why);
  solved = dr;
  return true;
}

}  // namespace bathyslam
