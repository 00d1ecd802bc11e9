#pragma once
// pipeline: the stages of design.md run in order for one configuration, with progress reported
// through a callback and cancellation checked between units of work.
#include <atomic>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/accept/acceptance.h"
#include "core/candidates/candidates.h"
#include "core/eval/metrics.h"
#include "core/filter/voxel_filter.h"
#include "core/graph/graph_check.h"
#include "core/graph/loop_consistency.h"
#include "core/graph/pose_graph.h"
#include "core/register/coarse_to_fine.h"
#include "core/register/gicp.h"
#include "core/submaps/submap.h"

namespace bathyslam {

enum class Configuration { kOdometry, kGicp, kMchs };
Configuration parse_configuration(const std::string& name);  // throws std::invalid_argument
std::string to_string(Configuration configuration);

struct PipelineConfig {
  Configuration configuration = Configuration::kGicp;
  SubmapConfig submaps;
  VoxelConfig voxel;
  CandidateConfig candidates;
  // GICP and the overlap crop for both registering configurations; the switch, matching,
  // RANSAC and the feature-aided refinement for `mchs`.
  CoarseToFineConfig registration;
  GraphConfig graph;
  ConsistencyConfig consistency;
  // `gicp`: every registration edge gets the same information, as in the paper's baseline: the
  // default weight of Table 1, its DR noise (5, 5, 1 m; 1e-4, 1e-4, 1e-2 rad). Chosen over
  // tighter sigmas on `lake` seeds 6-12, which no table reports (README, "The three
  // configurations"): from dead reckoning GICP keeps its guess's horizontal error, and on slopes
  // that error turns into a wrong depth, so a registration knows no more than a DR step does.
  Eigen::Vector3d gicp_sigma_translation_m{5.0, 5.0, 1.0};
  Eigen::Vector3d gicp_sigma_rotation_rad{1e-4, 1e-4, 1e-2};
  // `mchs`: the feature-aided path, the switch, loop closures, acceptance and quality weights.
  GridConfig grid;
  KeypointConfig keypoints;
  AcceptanceConfig acceptance;
  QualityConfig quality;
  // `mchs`'s defences against wrong edges (issue 14), each on by default; all 0 is the paper's
  // literal method.
  struct Robustness {
    // Every registration against the noise dead reckoning accumulates between its submaps.
    int dr_gate = 1;
    // Pairwise consistency (PCM) among the registrations that carry horizontal information.
    int consistency = 1;
    LoopConsistencyConfig consistency_config;  // its plausibility threshold is the gate's too
    // After the solve: lines tested against DR's noise, edges that pull beyond max_pull_sigma
    // dropped one at a time (at most max_drops), and dead reckoning published if that fails.
    int safety_net = 1;
    GraphCheckConfig check;
    double max_pull_sigma = 6.0;
    int max_drops = 20;
  } robustness;
  // `mchs` registers in survey order, this many submaps at a time, each batch predicted from
  // the trajectory corrected so far (pipeline.cpp, register_incrementally). 0: all at once,
  // every guess straight from dead reckoning, as `gicp` always does.
  int batch_submaps = 10;
  int threads = 0;  // 0: all cores
};

// Sets one parameter by its name ("gicp.max_correspondence_m", ...); throws
// std::invalid_argument naming the parameter when the name is unknown or the value out of range.
void set_parameter(PipelineConfig& config, const std::string& name, const std::string& value);
// The same for a number already parsed (a job's stored parameters, a report's).
void set_parameter(PipelineConfig& config, const std::string& name, double value);
// The same from one "name=value" argument (`--set`); a missing '=' is named too.
void set_parameter(PipelineConfig& config, std::string_view assignment);
// Every parameter by name with its current value.
std::map<std::string, double> parameters(const PipelineConfig& config);

enum class ConstraintType { kOdometry, kAdjacent, kLoop };
std::string to_string(ConstraintType type);

struct Constraint {
  ConstraintType type = ConstraintType::kOdometry;
  int from = 0, to = 0;
  Eigen::Isometry3d measured = Eigen::Isometry3d::Identity();  // `to` in the frame of `from`
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();  // registrations: overlap centroid, `to`'s frame
  // Registrations: the predicted pose of `to` in `from` the pair was registered from (the
  // feature-aided path starts GICP from RANSAC's estimate instead).
  Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
  Information6 information = Information6::Identity();
  RegistrationQuality quality;   // registrations only
  double overlap_fraction = 0;   // registrations only: footprint overlap at candidate time
  // `mchs` registrations: the path the switch chose and why, and the feature statistics.
  std::string path;              // "direct" or "feature-aided"
  std::string path_reason;
  double feature_density = 0;
  int matches = 0;
  double inlier_ratio = 0;
  int competitor_inliers = 0;    // RANSAC's best distinct alternative
  double competitor_separation_m = 0;
  Uniqueness uniqueness;         // the terrain probed around the answer (register/uniqueness.h)
  double dr_mahalanobis2 = -1;   // the DR gate's statistic (x, y, yaw); negative: not tested
  bool accepted = true;
  std::string reason;            // why a registration was rejected
  // An accepted registration that the back end left out of the graph (inconsistent with the
  // others, or dropped by the safety net), and why.
  std::string excluded;
  bool in_graph() const { return accepted && excluded.empty(); }
};

// What the safety net found after the solve and what it did.
struct SafetyNet {
  bool ran = false;
  bool pass = true;           // the published solution passed
  bool fell_back = false;     // it did not: dead reckoning was published instead
  std::string verdict;        // one line for people
  GraphCheck check;           // of the published solution (or of the last one tried)
  std::vector<std::string> dropped;  // each edge it dropped, with the reason
};

// Odometry constraints: consecutive submaps, DR relative pose, the graph's DR information
// (Table 1's by default).
std::vector<Constraint> odometry_constraints(const std::vector<Eigen::Isometry3d>& dead_reckoning, const GraphConfig& graph);

struct StageTiming {
  std::string stage;
  double seconds = 0;
};

struct PipelineResult {
  PipelineConfig config;
  SubmapSet submaps;
  std::vector<Eigen::Isometry3d> dr_poses;
  std::vector<Eigen::Isometry3d> optimized_poses;
  std::vector<Constraint> constraints;
  GraphSolution graph;
  SafetyNet safety_net;
  std::vector<double> dr_trajectory_errors, trajectory_errors;  // per submap with a reference
  // The same after the best rigid 2D alignment onto the reference (eval/metrics.h).
  std::vector<double> dr_aligned_trajectory_errors, aligned_trajectory_errors;
  ConsistencyReport dr_consistency, consistency;
  std::vector<StageTiming> timings;
};

using ProgressFn = std::function<void(std::string_view stage, double fraction)>;

class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("cancelled") {}
};

PipelineResult run_pipeline(const Survey& survey, const PipelineConfig& config,
                            const ProgressFn& progress = {}, const std::atomic<bool>* cancel = nullptr);

// The optimized navigation: every DR sample moved by its submaps' correction (interpolated
// between submap middles), in the nav.csv columns.
std::vector<NavSample> corrected_navigation(const Survey& survey, const PipelineResult& result);

}  // namespace bathyslam
