#include "core/pipeline/pipeline.h"

#include <chrono>
#include <cmath>
#include <mutex>
#include <thread>
#include <type_traits>

#include <omp.h>

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
  visit("gicp.max_correspondence_m", c.gicp.max_correspondence_m, 0.01, 100);
  visit("gicp.max_iterations", c.gicp.max_iterations, 1, 10000);
  visit("gicp.convergence", c.gicp.convergence, 1e-12, 1);
  visit("gicp.neighbours", c.gicp.neighbours, 3, 200);
  visit("gicp.refine_correspondence_m", c.gicp.refine_correspondence_m, 0, 100);
  visit("gicp.refine_convergence", c.gicp.refine_convergence, 1e-12, 1);
  visit("gicp.about_centroid", c.gicp.about_centroid, 0, 1);
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
  visit("eval.cell_m", c.consistency.cell_m, 0.05, 100);
  visit("eval.min_soundings", c.consistency.min_soundings, 1, 1000);
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

// Registers every candidate pair in parallel; results land in pair order.
std::vector<Constraint> register_candidates(const PipelineResult& r, const std::vector<CandidatePair>& pairs,
                                            const std::vector<Cloud::Ptr>& clouds, const PipelineConfig& config,
                                            const ProgressFn& progress, const std::atomic<bool>* cancel) {
  std::vector<Constraint> constraints(pairs.size());
  const Information6 uniform = information_from_sigmas(config.gicp_sigma_translation_m, config.gicp_sigma_rotation_rad);
  const int threads = config.threads > 0 ? config.threads : static_cast<int>(std::thread::hardware_concurrency());
  std::mutex progress_mutex;
  std::size_t finished = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    if (cancel != nullptr && cancel->load()) continue;
    const CandidatePair& pair = pairs[k];
    const Eigen::Isometry3d guess = r.dr_poses[pair.target].inverse() * r.dr_poses[pair.source];
    const Cloud::Ptr target = crop_to_overlap(*clouds[pair.target], *clouds[pair.source], guess.inverse(), 1.0);
    const Cloud::Ptr source = crop_to_overlap(*clouds[pair.source], *clouds[pair.target], guess, 1.0);
    const Registration reg = register_gicp(target, source, guess, config.gicp);
    Constraint& c = constraints[k];
    c.type = ConstraintType::kAdjacent;
    c.from = pair.target;
    c.to = pair.source;
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const pcl::PointXYZ& p : *source) centroid += p.getVector3fMap().cast<double>();
    if (!source->empty()) centroid /= static_cast<double>(source->size());
    c.measured = keep_dr_roll_pitch(reg.source_to_target, guess, centroid);
    c.anchor = centroid;
    c.quality = reg.quality;
    c.overlap_fraction = pair.overlap_fraction;
    c.information = uniform;
    // The baseline keeps every registration GICP reports as converged with some overlap.
    c.accepted = reg.quality.converged && reg.quality.overlap_points > 0;
    if (!reg.quality.converged) c.reason = "GICP did not converge";
    else if (reg.quality.overlap_points == 0) c.reason = "no overlapping points";
    if (progress) {
      std::lock_guard lock(progress_mutex);
      progress("register", static_cast<double>(++finished) / pairs.size());
    }
  }
  check(cancel);
  return constraints;
}

}  // namespace

Configuration parse_configuration(const std::string& name) {
  if (name == "odometry") return Configuration::kOdometry;
  if (name == "gicp") return Configuration::kGicp;
  throw std::invalid_argument("unknown configuration '" + name + "' (expected odometry or gicp)");
}

std::string to_string(Configuration c) { return c == Configuration::kOdometry ? "odometry" : "gicp"; }

std::string to_string(ConstraintType t) { return t == ConstraintType::kOdometry ? "odometry" : "adjacent"; }

void set_parameter(PipelineConfig& config, const std::string& name, const std::string& value) {
  bool found = false;
  visit_parameters(config, [&](std::string_view key, auto& field, double min, double max) {
    if (key != name) return;
    found = true;
    using Field = std::remove_reference_t<decltype(field)>;
    constexpr bool integer = std::is_integral_v<Field>;
    double v = 0;
    std::size_t used = 0;
    try {
      v = std::stod(value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != value.size() || !std::isfinite(v)) {
      throw std::invalid_argument("parameter '" + name + "': '" + value + "' is not a number");
    }
    if (v < min || v > max || (integer && v != std::floor(v))) {
      throw std::invalid_argument("parameter '" + name + "': " + value + " is outside [" +
                                  std::to_string(min) + ", " + std::to_string(max) + "]" +
                                  (integer ? " or not an integer" : ""));
    }
    field = static_cast<Field>(v);
  });
  if (!found) throw std::invalid_argument("unknown parameter '" + name + "'");
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

  // Odometry edges: consecutive submaps, DR relative pose, Table 1's DR information.
  const Information6 dr_information =
      information_from_sigmas(config.graph.dr_sigma_translation_m, config.graph.dr_sigma_rotation_rad);
  for (std::size_t i = 1; i < r.dr_poses.size(); ++i) {
    Constraint c;
    c.from = static_cast<int>(i - 1);
    c.to = static_cast<int>(i);
    c.measured = r.dr_poses[i - 1].inverse() * r.dr_poses[i];
    c.information = dr_information;
    r.constraints.push_back(c);
  }

  if (config.configuration == Configuration::kGicp) {
    report("filter", 0);
    std::vector<Cloud::Ptr> clouds(r.submaps.submaps.size());
#pragma omp parallel for schedule(dynamic, 4)
    for (std::size_t i = 0; i < clouds.size(); ++i) clouds[i] = voxel_filter(r.submaps.submaps[i].points, config.voxel);
    clock.done("filter");
    check(cancel);

    report("candidates", 0);
    const std::vector<CandidatePair> pairs = adjacent_line_candidates(r.submaps, r.dr_poses, config.candidates);
    clock.done("candidates");

    report("register", 0);
    for (Constraint& c : register_candidates(r, pairs, clouds, config, progress, cancel)) r.constraints.push_back(c);
    clock.done("register");
  }

  report("graph", 0);
  std::vector<PoseGraphEdge> edges;
  for (const Constraint& c : r.constraints) {
    if (c.accepted) {
      edges.push_back({c.from, c.to, c.measured, c.information, c.type != ConstraintType::kOdometry, c.anchor});
    }
  }
  r.graph = optimize_pose_graph(r.dr_poses, edges, config.graph);
  r.optimized_poses = r.graph.poses;
  clock.done("graph");
  check(cancel);

  report("eval", 0);
  r.dr_trajectory_errors = trajectory_errors(r.submaps, r.dr_poses);
  r.trajectory_errors = trajectory_errors(r.submaps, r.optimized_poses);
  r.dr_consistency = consistency_error(r.submaps, r.dr_poses, config.consistency);
  r.consistency = consistency_error(r.submaps, r.optimized_poses, config.consistency);
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
