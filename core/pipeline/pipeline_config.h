#pragma once
// Everything a pipeline run is configured by. A configuration (odometry, gicp, mchs) is a preset
// of these fields; each field can then be changed by name (parameters.h), so every ablation is
// a `--set` rather than code. The driver reads only the Plan drawn from them once.
#include <array>
#include <string>

#include <Eigen/Core>

#include "core/accept/acceptance.h"
#include "core/candidates/candidates.h"
#include "core/eval/metrics.h"
#include "core/features/terrain_grid.h"
#include "core/features/tsd_keypoints.h"
#include "core/filter/voxel_filter.h"
#include "core/graph/graph_check.h"
#include "core/graph/loop_consistency.h"
#include "core/graph/navigation_noise.h"
#include "core/graph/pose_graph.h"
#include "core/register/coarse_to_fine.h"
#include "core/submaps/submap.h"
#include "core/types/fields.h"

namespace bathyslam {

enum class Configuration { kOdometry, kGicp, kMchs };

// The names, in one place: the CLI's choices, the service's check and the report use these.
inline constexpr std::array<const char*, 3> kConfigurationNames{"odometry", "gicp", "mchs"};
Configuration parse_configuration(const std::string& name);  // throws std::invalid_argument
std::string to_string(Configuration configuration);

struct PipelineConfig {
  // The preset this configuration started from, the name the report gives it.
  Configuration configuration = Configuration::kMchs;

  // Which stages run; the defaults are `mchs`'s.
  struct Stages {
    bool registration = true;   // 0: dead reckoning's odometry alone
    bool feature_aided = true;  // TSD features and the observability switch; 0: every pair direct GICP
    // Table 1 (b)'s acceptance and quality-weighted information; 0: every converged registration
    // with uniform_information, as in the paper's baseline.
    bool quality_aware = true;
    bool loop_closures = true;  // loop-closure candidates beside the adjacent survey lines
    // Register in survey order this many submaps at a time, each batch predicted from the
    // trajectory corrected so far (pipeline.cpp, register_incrementally). 0: every pair at
    // once, every guess straight from dead reckoning.
    int batch_submaps = 10;

    template <typename Field>
    void fields(Field&& field) {
      field("registration", registration, 0, 1);
      field("feature_aided", feature_aided, 0, 1);
      field("quality_aware", quality_aware, 0, 1);
      field("loop_closures", loop_closures, 0, 1);
      field("batch_submaps", batch_submaps, 0, 1000000);
    }
  } stages;

  SubmapConfig submaps;
  VoxelConfig voxel;
  CandidateConfig candidates;
  // GICP and the overlap crop for every registration; the switch, matching, RANSAC and the
  // feature-aided refinement when stages.feature_aided.
  CoarseToFineConfig registration;
  GridConfig grid;
  KeypointConfig keypoints;
  AcceptanceConfig acceptance;
  QualityConfig quality;

  // Without stages.quality_aware every registration edge gets this information, as in the
  // paper's baseline: the default weight of Table 1, its DR noise (5, 5, 1 m; 1e-4, 1e-4,
  // 1e-2 rad). From dead reckoning GICP keeps its guess's horizontal error, and on slopes that
  // error turns into a wrong depth, so a registration knows no more than a DR step does
  // (docs/slam-core.md, "The three configurations", has the comparison).
  struct UniformInformation {
    Eigen::Vector3d sigma_translation_m{5.0, 5.0, 1.0};
    Eigen::Vector3d sigma_rotation_rad{1e-4, 1e-4, 1e-2};

    template <typename Field>
    void fields(Field&& field) {
      xyz("sigma_translation_m", sigma_translation_m, 1e-4, 1e3, field);
      rpy("sigma_rotation_rad", sigma_rotation_rad, 1e-6, 10, field);
    }
  } uniform_information;

  GraphConfig graph;
  // The DR sigmas above as a prior: the survey's own are estimated from its registrations
  // (navigation_noise.h) and used by the graph, the gates and the safety net.
  NavigationNoiseConfig navigation_noise;

  // Loop closures whose overlap has too few features to match (issue 31): registered by the
  // direct path from the batch's guess and judged as any registration is: the uniqueness probe,
  // the start check, the alias rule, the DR gate, PCM and the safety net. `reach_sigmas` > 0
  // keeps their horizontal information only where dead reckoning's noise between the two submaps
  // keeps the truth where a wrong answer would show (its horizontal sigma times `reach_sigmas`
  // within the probe's registration.uniqueness.search_radius_m with robustness.alias_from_prior,
  // else within registration.gicp.max_correspondence_m); beyond it they give depth, roll and
  // pitch. Off (0) by default: before the survey's noise is estimated that sigma is Table 1's
  // (tens of metres across a `small` survey), and on channels, where no adjacent answer is
  // unique, it took every loop's position away and with it every gain, while the other tests
  // kept all 84 matrix runs safe without it (docs/slam-every-seabed.md). enabled 0: refused, as
  // in the paper.
  struct DirectLoops {
    bool enabled = true;
    double reach_sigmas = 0.0;

    template <typename Field>
    void fields(Field&& field) {
      field("enabled", enabled, 0, 1);
      field("reach_sigmas", reach_sigmas, 0, 100);
    }
  } direct_loops;

  // The defences against wrong edges (issue 14); all 0 is the paper's literal method.
  struct Robustness {
    // Every registration against the noise dead reckoning accumulates between its submaps.
    bool dr_gate = true;
    // Pairwise consistency (PCM) among the registrations that carry horizontal information.
    bool consistency = true;
    LoopConsistencyConfig pcm;  // its plausibility threshold is the DR gate's too
    // After the solve: lines tested against DR's noise, edges that pull beyond max_pull_sigma
    // dropped one at a time (at most max_drops), and dead reckoning published if that fails.
    bool safety_net = true;
    // On a periodic or weakly textured seabed a registration's terrain also fits elsewhere (the
    // uniqueness probe's competitors). When dead reckoning rules every competitor out (each fails
    // the DR gate) the answer stands; when it does not, it keeps only what holds at any competitor
    // dead reckoning allows (resolve_alias: widened along them or depth, roll and pitch only; a
    // feature-aided answer so too, or refused: quality.feature_aliases_as_direct). 0: issue 14's
    // uniqueness test.
    bool alias_from_prior = true;
    // Where dead reckoning leaves an answer's competitors open, the graph of the registrations
    // kept so far may not: each batch judges them again against where that graph puts the two
    // submaps (its covariance, which only shrinks DR's), in up to `alias_graph_rounds` rounds, each
    // solving the graph with what the last kept. On a lawnmower over sand waves the pairs near a
    // turn are a short DR chain apart, and once they hold, the next pairs along the lines are too
    // (docs/slam-every-seabed.md). Off: on `lake`-sized sand waves it took paper drift from 26.7 to
    // 14.7 m, but under a heading walk it bent the survey to 34.6 m against dead reckoning's 21.2,
    // a wrong verdict's error carried into the next predictions with the graph's covariance still
    // tight. 0 (the default): dead reckoning alone judges.
    bool alias_from_graph = false;
    int alias_graph_rounds = 10;
    GraphCheckConfig line_check;
    double max_pull_sigma = 6.0;
    int max_drops = 20;
    // The last test, of the map: the solved map is published unless its consistency RMSE is above
    // dead reckoning's or its p99 above an upper confidence bound of dead reckoning's p99, the
    // quantile's own sampling noise: 2 with the cells drawn in blocks of a submap's extent
    // (p99_upper_by_blocks: a submap's cells move together), 1 with every cell its own sample
    // (ConsistencyReport::p99_upper, far tighter); 0 (issue 14) refuses any rise of the p99.
    int publish_rule = 2;

    template <typename Field>
    void fields(Field&& field) {
      field("dr_gate", dr_gate, 0, 1);
      field("consistency", consistency, 0, 1);
      nested("pcm", pcm, field);
      field("safety_net", safety_net, 0, 1);
      nested("line_check", line_check, field);
      field("max_pull_sigma", max_pull_sigma, 0.1, 1e6);
      field("max_drops", max_drops, 0, 100000);
      field("alias_from_prior", alias_from_prior, 0, 1);
      field("alias_from_graph", alias_from_graph, 0, 1);
      field("alias_graph_rounds", alias_graph_rounds, 1, 1000);
      field("publish_rule", publish_rule, 0, 2);
    }
  } robustness;

  ConsistencyConfig consistency;  // the evaluation's, of the published map
  int threads = 0;                // 0: all cores

  // Every length above (a parameter named *_m, an area *_m2, the registration's best sigmas) is
  // Table 1's, for the paper's survey: a T20-S ten metres over a lake bed, its soundings about
  // kPaperSpacingM apart. A survey whose soundings lie `scale` times as far apart gets every length
  // left at its preset's value `scale` times longer (scaled_to_footprint, parameters.h), so that a
  // grid cell, a voxel or a correspondence distance holds as many soundings at 80 m altitude or in
  // 2 km of water as in the lake.
  struct FootprintScale {
    // 0: measured (length_scale, sounding_footprint.h: the power of two nearest the survey's
    // sounding spacing over kPaperSpacingM); 1: Table 1's lengths as they are.
    double scale = 0;
    template <typename Field>
    void fields(Field&& field) {
      field("scale", scale, 0, 65536);
    }
  } footprint;

  template <typename Field>
  void fields(Field&& field) {
    nested("stages", stages, field);
    nested("submaps", submaps, field);
    nested("voxel", voxel, field);
    nested("candidates", candidates, field);
    nested("registration", registration, field);
    nested("grid", grid, field);
    nested("keypoints", keypoints, field);
    nested("acceptance", acceptance, field);
    nested("quality", quality, field);
    nested("uniform_information", uniform_information, field);
    nested("graph", graph, field);
    nested("navigation_noise", navigation_noise, field);
    nested("direct_loops", direct_loops, field);
    nested("robustness", robustness, field);
    nested("consistency", consistency, field);
    field("threads", threads, 0, 1024);
    nested("footprint", footprint, field);
  }
};

// The configuration's preset: `mchs` is the defaults; `gicp` the paper's baseline (direct GICP
// on adjacent lines from dead reckoning, uniform information, no defences); `odometry` dead
// reckoning alone.
PipelineConfig preset_config(Configuration configuration);

// What the driver does, decided once from the configuration.
struct Plan {
  bool registration = false;   // register candidate pairs at all
  bool features = false;       // TSD features and the feature-aided path
  bool quality_aware = false;  // acceptance tests and quality-weighted information
  bool loop_closures = false;
  int batch_submaps = 0;       // 0: one batch of every submap
  bool dr_gate = false, consistency = false, safety_net = false;
  bool direct_loops = false;      // loop closures without features by the direct path, within reach
  bool estimate_noise = false;    // the survey's own DR noise instead of Table 1's
  bool alias_from_prior = false;  // aliases dead reckoning rules out do not refuse an answer
  bool alias_from_graph = false;  // ... nor those the graph kept so far rules out, batch by batch
  bool own_gicp = false;             // our GICP on prepared submaps, else PCL's on filtered clouds
  bool hessian_information = false;  // registrations' information shaped by the GICP cost's Hessian
  int threads = 0;             // resolved: at least 1
};
Plan plan_of(const PipelineConfig& config);

}  // namespace bathyslam
