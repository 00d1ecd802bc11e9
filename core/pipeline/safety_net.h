#pragma once
// The safety net (issue 14): the solution is checked against dead reckoning's noise and the map
// against dead reckoning's own before anything is published; where the data do not support the
// solution, dead reckoning is published and the report says why.
#include <optional>
#include <string>
#include <vector>

#include "core/eval/metrics.h"
#include "core/graph/graph_check.h"
#include "core/graph/pose_graph.h"
#include "core/pipeline/constraint.h"
#include "core/pipeline/pipeline_config.h"

namespace bathyslam {

// What the safety net found after the solve and what it did.
struct SafetyNet {
  bool ran = false;
  bool pass = true;           // the published solution passed
  bool fell_back = false;     // it did not: dead reckoning was published instead
  std::string verdict;        // one line for people
  GraphCheck check;           // of the published solution (or of the last one tried)
  std::vector<std::string> dropped;  // each edge it dropped, with the reason
};

// The back end's answer: the solution to publish, and what the safety net did on the way.
struct Publication {
  GraphSolution graph;
  SafetyNet safety_net;
};

// Solves, then tests the solution (graph_check.h): while a line's odometry residuals fail the
// chi-square test or a registration pulls beyond `max_pull_sigma`, the hardest-pulling
// registration is dropped (its exclusion in `constraints` says why) and the graph solved again;
// when that does not end in a passing solution, dead reckoning is published and the verdict says
// so. `line_of_node`: each submap's survey line.
Publication solve_with_safety_net(const std::vector<Eigen::Isometry3d>& dr_poses, const std::vector<int>& line_of_node,
                                  std::vector<Constraint>& constraints, const GraphConfig& graph,
                                  const PipelineConfig::Robustness& robustness);

// `net`, of a graph solved again after an earlier solve (`earlier`) had dropped edges from it:
// the earlier drops listed first, and a pass counts both solves' drops.
void count_earlier_drops(SafetyNet& net, const SafetyNet& earlier);

// Dead reckoning instead of `published`, for the reason `verdict` gives. No registration enters
// the published map: each in `constraints` says so, so that the report's accepted edges are those
// the map was made with.
void publish_dead_reckoning(Publication& published, const std::vector<Eigen::Isometry3d>& dr_poses,
                            std::vector<Constraint>& constraints, const std::string& verdict);

// The last test needs no reference: a map is published only when it agrees with itself better
// than dead reckoning's does as a whole: its consistency RMSE over the cells two lines share no
// higher, and its p99 no higher than dead reckoning's could be by the sampling of its cells alone
// (robustness.publish_rule 2: the cells drawn in blocks of a submap, p99_upper_by_blocks; 1: each
// cell on its own, ConsistencyReport::p99_upper; 0: no higher than dead reckoning's p99).
// Returns why the data do not support the solved map, or nullopt when they do.
std::optional<std::string> less_consistent_than_dead_reckoning(const ConsistencyReport& solved, const ConsistencyReport& dr,
                                                               const SubmapSet& submaps,
                                                               const std::vector<Eigen::Isometry3d>& dr_poses,
                                                               const PipelineConfig& config);

// The publication rule on the evaluated map: when `solved` (the map of `published`) is less
// consistent than dead reckoning's `dr`, dead reckoning is published instead, with the reason,
// and `solved` becomes dead reckoning's report. Returns whether it fell back.
bool fall_back_unless_more_consistent(Publication& published, ConsistencyReport& solved, const ConsistencyReport& dr,
                                      const SubmapSet& submaps, const std::vector<Eigen::Isometry3d>& dr_poses,
                                      std::vector<Constraint>& constraints, const PipelineConfig& config);

}  // namespace bathyslam
