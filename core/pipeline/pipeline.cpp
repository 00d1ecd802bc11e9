#include "core/pipeline/pipeline.h"

#include <charconv>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>
#include <thread>
#include <type_traits>

#include <omp.h>

#include "core/pipeline/robust_backend.h"
#include "core/sync/nav_interpolation.h"

namespace bathyslam {
namespace {

// Calls `visit(name, field, min, max)` for every tunable parameter, `field` being a reference to
// the config's own member (double, float or int): one list serves reading and setting.
template <typename Config, typename Visit>
void visit_parameters(Config& c, Visit&& visit) {
  visit("submaps.pings_per_submap", c.submaps.pings_per_submap, 10, 10000);
  visit("voxel.leaf_x_m", c.voxel.leaf_x_m, 0.01, 10);
  visit("voxel.leaf_y_m", c.voxel.leaf_y_m, 0.01, 10);
  visit("voxel.leaf_z_m", c.voxel.leaf_z_m, 0.01, 10);
  visit("candidates.k_adjacent_lines", c.candidates.k_adjacent_lines, 1, 100);
  visit("candidates.parallel_tolerance_deg", c.candidates.parallel_tolerance_deg, 0, 90);
  visit("candidates.min_overlap_fraction", c.candidates.min_overlap_fraction, 0, 1);
  visit("candidates.loop_min_submap_gap", c.candidates.loop_min_submap_gap, 1, 100000);
  visit("gicp.max_correspondence_m", c.registration.gicp.max_correspondence_m, 0.01, 100);
  visit("gicp.max_iterations", c.registration.gicp.max_iterations, 1, 10000);
  visit("gicp.convergence", c.registration.gicp.convergence, 1e-12, 1);
  visit("gicp.neighbours", c.registration.gicp.neighbours, 3, 200);
  visit("gicp.refine_correspondence_m", c.registration.gicp.refine_correspondence_m, 0, 100);
  visit("gicp.refine_convergence", c.registration.gicp.refine_convergence, 1e-12, 1);
  visit("register.crop_margin_m", c.registration.crop_margin_m, 0, 100);
  visit("register.feature_refine_correspondence_m", c.registration.feature_refine_correspondence_m, 0, 100);
  visit("gicp.about_centroid", c.registration.gicp.about_centroid, 0, 1);
  visit("gicp.engine", c.registration.gicp.engine, 0, 1);
  visit("gicp.min_observed_share", c.registration.gicp.min_observed_share, 0, 1);
  visit("gicp.sigma_x_m", c.gicp_sigma_translation_m.x(), 1e-4, 1e3);
  visit("gicp.sigma_y_m", c.gicp_sigma_translation_m.y(), 1e-4, 1e3);
  visit("gicp.sigma_z_m", c.gicp_sigma_translation_m.z(), 1e-4, 1e3);
  visit("gicp.sigma_roll_rad", c.gicp_sigma_rotation_rad.x(), 1e-6, 10);
  visit("gicp.sigma_pitch_rad", c.gicp_sigma_rotation_rad.y(), 1e-6, 10);
  visit("gicp.sigma_yaw_rad", c.gicp_sigma_rotation_rad.z(), 1e-6, 10);
  visit("graph.dr_sigma_x_m", c.graph.dr_sigma_translation_m.x(), 1e-4, 1e3);
  visit("graph.dr_sigma_y_m", c.graph.dr_sigma_translation_m.y(), 1e-4, 1e3);
  visit("graph.dr_sigma_z_m", c.graph.dr_sigma_translation_m.z(), 1e-4, 1e3);
  visit("graph.dr_sigma_roll_rad", c.graph.dr_sigma_rotation_rad.x(), 1e-8, 10);
  visit("graph.dr_sigma_pitch_rad", c.graph.dr_sigma_rotation_rad.y(), 1e-8, 10);
  visit("graph.dr_sigma_yaw_rad", c.graph.dr_sigma_rotation_rad.z(), 1e-8, 10);
  visit("graph.huber_delta", c.graph.huber_delta, 1e-3, 1e3);
  visit("graph.max_iterations", c.graph.max_iterations, 1, 10000);
  visit("grid.cell_m", c.grid.cell_m, 0.05, 20);
  visit("grid.idw_radius_cells", c.grid.idw_radius_cells, 0.5, 10);
  visit("keypoints.percentile", c.keypoints.percentile, 0, 100);
  visit("keypoints.descriptor_size", c.keypoints.descriptor_size, 3, 63);
  visit("keypoints.min_tsd_m", c.keypoints.min_tsd_m, 0, 100);
  visit("keypoints.suppression_radius", c.keypoints.suppression_radius, 0, 50);
  visit("matching.max_distance_m", c.registration.matching.max_distance_m, 0.1, 1000);
  visit("matching.min_ncc", c.registration.matching.min_ncc, -1, 1);
  visit("matching.ratio", c.registration.matching.ratio, 0.01, 1);
  visit("matching.min_matches", c.registration.matching.min_matches, 3, 100000);
  visit("ransac.max_iterations", c.registration.ransac.max_iterations, 1, 1000000);
  visit("ransac.initial_threshold_m", c.registration.ransac.initial_threshold_m, 0.01, 100);
  visit("ransac.min_threshold_m", c.registration.ransac.min_threshold_m, 0.001, 100);
  visit("ransac.target_inlier_ratio", c.registration.ransac.target_inlier_ratio, 0.01, 1);
  visit("switch.min_feature_density", c.registration.switching.min_feature_density, 0, 1);
  visit("accept.min_inlier_ratio", c.acceptance.min_inlier_ratio, 0, 1);
  visit("accept.max_overlap_mse_m2", c.acceptance.max_overlap_mse_m2, 0, 1000);
  visit("accept.min_overlap_points", c.acceptance.min_overlap_points, 0, 10000000);
  visit("accept.max_translation_m", c.acceptance.max_translation_m, 0, 100000);
  visit("accept.max_competitor_ratio", c.acceptance.max_competitor_ratio, 0, 1);
  visit("ransac.competitor_separation_m", c.registration.ransac.competitor_separation_m, 0.01, 1000);
  visit("accept.min_distinctness", c.acceptance.min_distinctness, 0, 1e6);
  visit("uniqueness.search_radius_m", c.registration.uniqueness.search_radius_m, 1, 1000);
  visit("uniqueness.step_m", c.registration.uniqueness.step_m, 0.1, 100);
  visit("uniqueness.exclusion_m", c.registration.uniqueness.exclusion_m, 0, 1000);
  visit("uniqueness.local_radius_m", c.registration.uniqueness.local_radius_m, 0, 1000);
  visit("quality.sigma_x_m", c.quality.best_sigma_translation_m.x(), 1e-4, 1e3);
  visit("quality.sigma_y_m", c.quality.best_sigma_translation_m.y(), 1e-4, 1e3);
  visit("quality.sigma_z_m", c.quality.best_sigma_translation_m.z(), 1e-4, 1e3);
  visit("quality.sigma_roll_rad", c.quality.best_sigma_rotation_rad.x(), 1e-6, 10);
  visit("quality.sigma_pitch_rad", c.quality.best_sigma_rotation_rad.y(), 1e-6, 10);
  visit("quality.sigma_yaw_rad", c.quality.best_sigma_rotation_rad.z(), 1e-6, 10);
  visit("quality.direct_horizontal_share", c.quality.direct_horizontal_share, 0, 1);
  visit("quality.direct_depth_from_relief", c.quality.direct_depth_from_relief, 0, 1);
  visit("quality.information_from_hessian", c.quality.information_from_hessian, 0, 1);
  visit("quality.hessian_full_share", c.quality.hessian_full_share, 1e-6, 1);
  visit("quality.hessian_zero_share", c.quality.hessian_zero_share, 0, 1);
  visit("robust.dr_gate", c.robustness.dr_gate, 0, 1);
  visit("robust.plausibility_chi2", c.robustness.consistency_config.plausibility.chi2_threshold, 0.01, 1e6);
  visit("robust.consistency", c.robustness.consistency, 0, 1);
  visit("robust.pair_chi2", c.robustness.consistency_config.pair_chi2_threshold, 0.01, 1e6);
  visit("robust.safety_net", c.robustness.safety_net, 0, 1);
  visit("robust.safety_net_p", c.robustness.check.p, 0.5, 0.999999);
  visit("robust.max_pull_sigma", c.robustness.max_pull_sigma, 0.1, 1e6);
  visit("robust.max_drops", c.robustness.max_drops, 0, 100000);
  visit("graph.dcs_phi", c.graph.dcs_phi, 1e-3, 1e6);
  visit("eval.cell_m", c.consistency.cell_m, 0.05, 100);
  visit("eval.min_soundings", c.consistency.min_soundings, 1, 1000);
  visit("batch_submaps", c.batch_submaps, 0, 1000000);
  visit("threads", c.threads, 0, 1024);
}

class StageClock {
 public:
  explicit StageClock(std::vector<StageTiming>& timings) : timings_(timings) {}
  void done(const std::string& stage) {
    const auto now = std::chrono::steady_clock::now();
    timings_.push_back({stage, std::chrono::duration<double>(now - start_).count()});
    start_ = now;
  }

 private:
  std::vector<StageTiming>& timings_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

void check(const std::atomic<bool>* cancel) {
  if (cancel != nullptr && cancel->load()) throw Cancelled();
}

struct TypedPair {
  CandidatePair pair;
  ConstraintType type = ConstraintType::kAdjacent;
};

// A registration's constraint, with DR roll and pitch kept (keep_dr_roll_pitch) and the
// switch's record; acceptance and information are the configuration's to set.
Constraint constraint_of(const TypedPair& typed, const PairRegistration& reg, const Eigen::Isometry3d& guess) {
  Constraint c;
  c.type = typed.type;
  c.from = typed.pair.target;
  c.to = typed.pair.source;
  c.measured = keep_dr_roll_pitch(reg.registration.source_to_target, guess, reg.anchor);
  c.anchor = reg.anchor;
  c.guess = guess;
  c.quality = reg.registration.quality;
  c.overlap_fraction = typed.pair.overlap_fraction;
  c.path = to_string(reg.path);
  c.path_reason = reg.why;
  c.feature_density = reg.feature_density;
  c.matches = reg.matches;
  c.inlier_ratio = reg.inlier_ratio;
  c.competitor_inliers = reg.competitor_inliers;
  c.competitor_separation_m = reg.competitor_separation_m;
  c.uniqueness = reg.uniqueness;
  return c;
}

// `gicp`: direct GICP from dead reckoning, every converged registration kept with the same
// information, as in the paper's baseline.
Constraint register_uniform(const std::vector<Eigen::Isometry3d>& estimate, const TypedPair& typed,
                            const std::vector<Cloud::Ptr>& clouds, GicpCloudCache& prepared, const PipelineConfig& config) {
  const CandidatePair& pair = typed.pair;
  const Eigen::Isometry3d guess = estimate[pair.target].inverse() * estimate[pair.source];
  const PairRegistration reg = register_direct(*clouds[pair.target], *clouds[pair.source], guess,
                                               config.registration.gicp, config.registration.crop_margin_m, false,
                                               prepared_pair(prepared, config.registration.gicp, pair.target, pair.source));
  Constraint c = constraint_of(typed, reg, guess);
  c.information = information_from_sigmas(config.gicp_sigma_translation_m, config.gicp_sigma_rotation_rad);
  c.accepted = c.quality.converged && c.quality.overlap_points > 0;
  if (c.quality.overlap_points == 0) c.reason = "no overlapping points";
  else if (!c.quality.converged) c.reason = "GICP did not converge";
  return c;
}

// `mchs`: the switch picks direct or feature-aided registration; acceptance decides whether the
// result becomes an edge, and its quality how much the edge weighs.
Constraint register_mchs(const std::vector<Eigen::Isometry3d>& estimate, const TypedPair& typed,
                         const std::vector<Cloud::Ptr>& clouds, GicpCloudCache& prepared, const std::vector<SubmapFeatures>& features,
                         const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses, const PipelineConfig& config) {
  const CandidatePair& pair = typed.pair;
  const Eigen::Isometry3d guess = estimate[pair.target].inverse() * estimate[pair.source];
  const uint64_t seed = config.registration.ransac.seed ^ (static_cast<uint64_t>(pair.target) << 32 | static_cast<uint64_t>(pair.source));
  CoarseToFineConfig registration = config.registration;
  registration.hessian = config.quality.information_from_hessian;  // the information needs it, nothing else does
  const PairRegistration reg = register_coarse_to_fine(*clouds[pair.target], *clouds[pair.source], features[pair.target],
                                                       features[pair.source], guess, registration, seed,
                                                       prepared_pair(prepared, registration.gicp, pair.target, pair.source));
  Constraint c = constraint_of(typed, reg, guess);
  c.reason = rejection_reason(reg, guess, config.acceptance, typed.type == ConstraintType::kLoop);
  c.accepted = c.reason.empty();
  const Eigen::Matrix3d level_from_target =
      level_from_body(Eigen::Quaterniond(estimate[pair.target].rotation())).toRotationMatrix();
  if (c.accepted) c.information = quality_information(reg, config.quality, level_from_target);
  if (config.robustness.dr_gate) gate_against_dead_reckoning(c, dr, dr_poses, config.robustness.consistency_config.plausibility);
  return c;
}

// Registers every pair in parallel from the guesses `estimate` gives; results in pair order.
std::vector<Constraint> register_pairs(const std::vector<Eigen::Isometry3d>& estimate, const std::vector<TypedPair>& pairs,
                                       const std::vector<Cloud::Ptr>& clouds, GicpCloudCache& prepared,
                                       const std::vector<SubmapFeatures>& features,
                                       const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses,
                                       const PipelineConfig& config, const std::atomic<bool>* cancel) {
  std::vector<Constraint> constraints(pairs.size());
  const int threads = config.threads > 0 ? config.threads : static_cast<int>(std::thread::hardware_concurrency());
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    if (cancel != nullptr && cancel->load()) continue;
    constraints[k] = config.configuration == Configuration::kMchs
                         ? register_mchs(estimate, pairs[k], clouds, prepared, features, dr, dr_poses, config)
                         : register_uniform(estimate, pairs[k], clouds, prepared, config);
  }
  check(cancel);
  return constraints;
}

// The candidates whose later submap lies in [begin, end), with footprints at `estimate`.
std::vector<TypedPair> candidates_ending_in(const PipelineResult& r, const std::vector<Eigen::Isometry3d>& estimate,
                                            int begin, int end, const PipelineConfig& config) {
  std::vector<TypedPair> pairs;
  auto take = [&](const std::vector<CandidatePair>& found, ConstraintType type) {
    for (const CandidatePair& p : found) {
      if (p.source >= begin && p.source < end) pairs.push_back({p, type});
    }
  };
  take(adjacent_line_candidates(r.submaps, estimate, config.candidates), ConstraintType::kAdjacent);
  if (config.configuration == Configuration::kMchs) {
    take(loop_candidates(r.submaps, estimate, config.candidates), ConstraintType::kLoop);
  }
  return pairs;
}

// Registration in survey order, a batch of submaps at a time, as a vehicle would map: each
// batch is predicted by dead reckoning from the trajectory corrected so far, its candidates are
// registered from that prediction, and the graph is solved before the next batch. A pair's
// guess then carries the drift of one batch rather than of everything between its two
// submaps, which across a lawnmower is tens of metres, far outside GICP's basin.
void register_incrementally(PipelineResult& r, const std::vector<Cloud::Ptr>& clouds,
                            const std::vector<SubmapFeatures>& features, const PipelineConfig& config,
                            const ProgressFn& progress, const std::atomic<bool>* cancel) {
  const int n = static_cast<int>(r.dr_poses.size());
  // The `gicp` baseline registers from dead reckoning, as the paper's does; fed back through
  // its uniform weights, its wrong flat-ground edges would steer every later guess.
  const bool incremental = config.configuration == Configuration::kMchs && config.batch_submaps > 0;
  const int batch = incremental ? config.batch_submaps : std::max(n, 1);
  std::vector<Eigen::Isometry3d> estimate = r.dr_poses;
  const DrNoiseModel dr(r.dr_poses, config.graph);
  const bool consistency = config.configuration == Configuration::kMchs && config.robustness.consistency;
  GicpCloudCache prepared(clouds, config.registration.gicp.neighbours);  // our GICP's, once per submap
  for (int begin = 0; begin < n; begin += batch) {
    const int end = std::min(n, begin + batch);
    for (int s = std::max(begin, 1); s < end; ++s) {
      estimate[s] = estimate[s - 1] * (r.dr_poses[s - 1].inverse() * r.dr_poses[s]);
    }
    const std::vector<TypedPair> pairs = candidates_ending_in(r, estimate, begin, end, config);
    for (Constraint& c : register_pairs(estimate, pairs, clouds, prepared, features, dr, r.dr_poses, config, cancel)) {
      r.constraints.push_back(c);
    }
    if (consistency) select_consistent_registrations(r.constraints, dr, r.dr_poses, config.robustness.consistency_config);
    if (end < n && !pairs.empty()) estimate = solve(estimate, r.constraints, config.graph).poses;
    if (progress) progress("register", static_cast<double>(end) / n);
  }
}

}  // namespace

Configuration parse_configuration(const std::string& name) {
  if (name == "odometry") return Configuration::kOdometry;
  if (name == "gicp") return Configuration::kGicp;
  if (name == "mchs") return Configuration::kMchs;
  throw std::invalid_argument("unknown configuration '" + name + "' (expected odometry, gicp or mchs)");
}

std::string to_string(Configuration c) {
  switch (c) {
    case Configuration::kOdometry: return "odometry";
    case Configuration::kGicp: return "gicp";
    case Configuration::kMchs: return "mchs";
  }
  return "?";
}

std::vector<Constraint> odometry_constraints(const std::vector<Eigen::Isometry3d>& dead_reckoning, const GraphConfig& graph) {
  const Information6 dr_information = information_from_sigmas(graph.dr_sigma_translation_m, graph.dr_sigma_rotation_rad);
  std::vector<Constraint> constraints;
  for (const PoseGraphEdge& e : odometry_edges(dead_reckoning, dr_information)) {
    Constraint c;
    c.from = e.from;
    c.to = e.to;
    c.measured = e.measured;
    c.information = e.information;
    constraints.push_back(c);
  }
  return constraints;
}

std::string to_string(ConstraintType t) {
  switch (t) {
    case ConstraintType::kOdometry: return "odometry";
    case ConstraintType::kAdjacent: return "adjacent";
    case ConstraintType::kLoop: return "loop";
  }
  return "?";
}

namespace {

// Sets `name` to `value` (nullopt: the text was not a number) after the range check; messages
// quote the value as the caller gave it (`shown`).
void assign_parameter(PipelineConfig& config, const std::string& name, std::optional<double> value,
                      const std::string& shown) {
  bool found = false;
  visit_parameters(config, [&](std::string_view key, auto& field, double min, double max) {
    if (key != name) return;
    found = true;
    using Field = std::remove_reference_t<decltype(field)>;
    constexpr bool integer = std::is_integral_v<Field>;
    if (!value || !std::isfinite(*value)) {
      throw std::invalid_argument("parameter '" + name + "': '" + shown + "' is not a number");
    }
    const double v = *value;
    if (v < min || v > max || (integer && v != std::floor(v))) {
      throw std::invalid_argument("parameter '" + name + "': " + shown + " is outside [" +
                                  std::to_string(min) + ", " + std::to_string(max) + "]" +
                                  (integer ? " or not an integer" : ""));
    }
    field = static_cast<Field>(v);
  });
  if (!found) throw std::invalid_argument("unknown parameter '" + name + "'");
}

}  // namespace

void set_parameter(PipelineConfig& config, const std::string& name, const std::string& value) {
  std::optional<double> number;
  try {
    std::size_t used = 0;
    const double v = std::stod(value, &used);
    if (used == value.size()) number = v;
  } catch (const std::exception&) {
  }
  assign_parameter(config, name, number, value);
}

void set_parameter(PipelineConfig& config, const std::string& name, double value) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  assign_parameter(config, name, value, std::string(text, end));
}

void set_parameter(PipelineConfig& config, std::string_view assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string_view::npos) {
    throw std::invalid_argument("expected name=value, got '" + std::string(assignment) + "'");
  }
  set_parameter(config, std::string(assignment.substr(0, eq)), std::string(assignment.substr(eq + 1)));
}

std::map<std::string, double> parameters(const PipelineConfig& config) {
  std::map<std::string, double> out;
  visit_parameters(config, [&](std::string_view key, const auto& field, double, double) {
    out[std::string(key)] = static_cast<double>(field);
  });
  return out;
}

PipelineResult run_pipeline(const Survey& survey, const PipelineConfig& config, const ProgressFn& progress,
                            const std::atomic<bool>* cancel) {
  auto report = [&](std::string_view stage, double fraction) {
    if (progress) progress(stage, fraction);
  };
  PipelineResult r;
  r.config = config;
  StageClock clock(r.timings);

  report("submaps", 0);
  r.submaps = build_submaps(survey, config.submaps);
  for (const Submap& s : r.submaps.submaps) r.dr_poses.push_back(s.dr_pose);
  clock.done("submaps");
  check(cancel);

  r.constraints = odometry_constraints(r.dr_poses, config.graph);

  if (config.configuration != Configuration::kOdometry) {
    report("filter", 0);
    std::vector<Cloud::Ptr> clouds(r.submaps.submaps.size());
#pragma omp parallel for schedule(dynamic, 4)
    for (std::size_t i = 0; i < clouds.size(); ++i) clouds[i] = voxel_filter(r.submaps.submaps[i].points, config.voxel);
    clock.done("filter");
    check(cancel);

    std::vector<SubmapFeatures> features;
    if (config.configuration == Configuration::kMchs) {
      report("features", 0);
      features.resize(r.submaps.submaps.size());
#pragma omp parallel for schedule(dynamic, 4)
      for (std::size_t i = 0; i < features.size(); ++i) {
        features[i] = extract_features(r.submaps.submaps[i], config.grid, config.keypoints);
      }
      clock.done("features");
      check(cancel);
    }

    report("register", 0);
    register_incrementally(r, clouds, features, config, progress, cancel);
    clock.done("register");
  }

  report("graph", 0);
  if (config.configuration == Configuration::kMchs && config.robustness.safety_net) {
    solve_with_safety_net(r, config);
  } else {
    r.graph = solve(r.dr_poses, r.constraints, config.graph);
  }
  r.optimized_poses = r.graph.poses;
  clock.done("graph");
  check(cancel);

  report("eval", 0);
  r.dr_consistency = consistency_error(r.submaps, r.dr_poses, config.consistency);
  r.consistency = consistency_error(r.submaps, r.optimized_poses, config.consistency);
  if (r.safety_net.ran && !r.safety_net.fell_back) fall_back_unless_more_consistent(r);
  r.dr_trajectory_errors = trajectory_errors(r.submaps, r.dr_poses);
  r.trajectory_errors = trajectory_errors(r.submaps, r.optimized_poses);
  r.dr_aligned_trajectory_errors = aligned_trajectory_errors(r.submaps, r.dr_poses);
  r.aligned_trajectory_errors = aligned_trajectory_errors(r.submaps, r.optimized_poses);
  clock.done("eval");
  report("done", 1);
  return r;
}

std::vector<NavSample> corrected_navigation(const Survey& survey, const PipelineResult& r) {
  const auto& submaps = r.submaps.submaps;
  const LocalOrigin& origin = r.submaps.origin;
  // Correction of each submap: optimized pose relative to its DR pose, in the map frame.
  std::vector<Eigen::Isometry3d> corrections;
  for (std::size_t i = 0; i < submaps.size(); ++i) corrections.push_back(r.optimized_poses[i] * r.dr_poses[i].inverse());
  auto correction_at = [&](double t) -> Eigen::Isometry3d {
    if (submaps.empty()) return Eigen::Isometry3d::Identity();
    if (t <= submaps.front().time_mid) return corrections.front();
    if (t >= submaps.back().time_mid) return corrections.back();
    const auto next = std::lower_bound(submaps.begin(), submaps.end(), t,
                                       [](const Submap& s, double time) { return s.time_mid < time; });
    const std::size_t b = static_cast<std::size_t>(next - submaps.begin()), a = b - 1;
    const double f = (t - submaps[a].time_mid) / (submaps[b].time_mid - submaps[a].time_mid);
    Eigen::Isometry3d c = Eigen::Isometry3d::Identity();
    c.linear() = Eigen::Quaterniond(corrections[a].rotation())
                     .slerp(f, Eigen::Quaterniond(corrections[b].rotation()))
                     .toRotationMatrix();
    c.translation() = (1 - f) * corrections[a].translation() + f * corrections[b].translation();
    return c;
  };
  std::vector<NavSample> out;
  out.reserve(survey.nav.size());
  for (const NavSample& s : survey.nav) {
    NavSample corrected = nav_from_pose(correction_at(s.time) * vehicle_pose(s, origin), origin);
    corrected.time = s.time;
    out.push_back(corrected);
  }
  return out;
}

}  // namespace bathyslam
