#pragma once
// pipeline: the stages of docs/design.md run in order for one configuration, with progress
// reported through a callback and cancellation checked between units of work.
#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/eval/metrics.h"
#include "core/fuse/difference.h"
#include "core/graph/graph_check.h"
#include "core/graph/navigation_noise.h"
#include "core/graph/pose_graph.h"
#include "core/pipeline/constraint.h"
#include "core/parallel/cancel.h"
#include "core/pipeline/parameters.h"
#include "core/pipeline/pipeline_config.h"
#include "core/pipeline/registration_checkpoint.h"
#include "core/pipeline/safety_net.h"
#include "core/submaps/submap.h"

namespace bathyslam {

struct StageTiming {
  std::string stage;
  double seconds = 0;
};

// A run's result, assembled from the stages' answers (pipeline.cpp: the register stage's
// Registrations, the back end's Publication, the Evaluation) once they are all in.
struct PipelineResult {
  // As run: the lengths of the configuration given scaled to the survey's footprint.
  PipelineConfig config;
  double footprint_scale = 1;  // of Table 1's lengths, for submaps.footprint (parameters.h)
  SubmapSet submaps;
  std::vector<Eigen::Isometry3d> dr_poses;
  std::vector<Eigen::Isometry3d> optimized_poses;
  std::vector<Constraint> constraints;
  GraphSolution graph;
  // The survey's own DR noise (navigation_noise.h), which the graph's odometry edges, the gates
  // and the safety net used; the prior's when not estimated.
  NavigationNoiseEstimate navigation_noise;
  SafetyNet safety_net;
  std::vector<double> dr_trajectory_errors, trajectory_errors;  // per submap with a reference
  // The same after the best rigid 2D alignment onto the reference (eval/metrics.h).
  std::vector<double> dr_aligned_trajectory_errors, aligned_trajectory_errors;
  ConsistencyReport dr_consistency, consistency;
  // Several surveys of one site: consistency within the surveys and across them.
  std::optional<SiteConsistency> dr_site_consistency, site_consistency;
  // Of those, registrations across surveys left without depth, roll and pitch because their
  // overlap holds change (discount_change_across_surveys).
  int registrations_over_change = 0;
  bool across_where_unchanged = false;  // site_consistency.across left out the changed cells
  std::vector<StageTiming> timings;
  // Within the register stage: the graph solves between its batches (how a growing survey's
  // graph costs, in the report's "graph" section).
  int batch_solves = 0;
  double batch_solve_seconds = 0;
  // The register stage's batches, and how many of them an earlier run's checkpoints gave.
  int batches = 0, batches_taken_up = 0;
};

using ProgressFn = std::function<void(std::string_view stage, double fraction)>;

// Throws Cancelled (cancel.h) once `cancel` is set.
PipelineResult run_pipeline(const Survey& survey, const PipelineConfig& config,
                            const ProgressFn& progress = {}, const std::atomic<bool>* cancel = nullptr);

// The same from submaps the caller built (build_submaps with `config.submaps`, or a reader
// streaming the pings into a SubmapBuilder, so that a survey's soundings are never held twice:
// docs/performance.md); `submaps_seconds`, the time that took, is the "submaps" stage's. With
// `checkpoints`, the register stage takes up the batches an earlier run of the same job stored
// and hands each batch it registers itself to `checkpoints->keep` (registration_checkpoint.h).
PipelineResult run_pipeline(SubmapSet submaps, double submaps_seconds, const PipelineConfig& config,
                            const ProgressFn& progress = {}, const std::atomic<bool>* cancel = nullptr,
                            const RegistrationCheckpoints* checkpoints = nullptr);

// Several surveys: a registration across two surveys whose overlap, at the solution, holds enough
// significant change (its mean over the overlap beyond the registration's vertical sigma) keeps
// its horizontal information only, and the graph is solved again, so that the change is not taken
// for the registration's misfit and shared out between the surveys (on `lake` a dredged cut
// pulled the first survey 0.12 m deeper around it and the difference lost two thirds of its
// volume: docs/sites.md). One round: the maps of the solution say where the change is. The
// consistency across the surveys is then counted where the seabed did not change. Returns how
// many registrations.
int discount_change_across_surveys(PipelineResult& r, const FuseConfig& fuse, const DifferenceConfig& difference);

}  // namespace bathyslam
