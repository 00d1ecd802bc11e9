#include "core/sim/simulator.h"

#include <cmath>
#include <stdexcept>

#include "core/sim/random.h"
#include "core/types/pose.h"

namespace bathyslam::sim {
namespace {

// Pings stay clear of the first and last second of navigation, as on a real vehicle where
// logging starts before and stops after the sonar.
constexpr double kNavLeadS = 1.0;

std::size_t steps_per(double interval_s, double step_s) {
  const auto n = static_cast<std::size_t>(std::lround(interval_s / step_s));
  if (n == 0 || std::abs(n * step_s - interval_s) > 1e-9) {
    throw std::invalid_argument("rates must be whole multiples of the simulation step");
  }
  return n;
}

}  // namespace

DriftModel parse_drift_model(const std::string& name) {
  if (name == "paper") return DriftModel::kPaper;
  if (name == "dvl") return DriftModel::kDvl;
  throw std::invalid_argument("unknown drift model '" + name + "' (expected paper or dvl)");
}

std::string to_string(DriftModel model) { return model == DriftModel::kPaper ? "paper" : "dvl"; }

Simulation simulate(const SimulationConfig& config) {
  MotionConfig motion = config.motion;
  motion.seed = config.seed;
  TerrainConfig terrain_config = config.terrain;
  terrain_config.seed = config.seed;

  const std::vector<LineSpec> lines = survey_pattern(config.scenario);
  const std::vector<VehicleState> states = drive(lines, motion);
  // Half a swath either side of the lines, plus room for turns.
  const double margin = 40.0 + 2.0 * terrain_config.mean_depth_m;
  Simulation sim;
  sim.terrain = Terrain::generate(terrain_config, pattern_area(lines, margin));

  Survey& survey = sim.survey;
  survey.metadata.name = to_string(config.scenario) + "-seed" + std::to_string(config.seed) +
                         "-" + to_string(config.drift);
  survey.metadata.crs = config.crs;

  // Navigation at its rate from the first step; pings at theirs, offset by one step so ping
  // times fall between navigation samples and the sync stage really interpolates.
  const std::size_t nav_stride = steps_per(1.0 / config.nav_rate_hz, motion.step_s);
  const std::size_t ping_stride = steps_per(1.0 / config.sonar.ping_rate_hz, motion.step_s);
  const std::size_t lead = steps_per(kNavLeadS, motion.step_s);
  std::vector<NavSample> truth =
      navigation_of(states, nav_stride, config.origin_easting, config.origin_northing);
  std::vector<std::size_t> ping_steps;
  for (std::size_t i = lead + 1; i + lead < states.size(); i += ping_stride) ping_steps.push_back(i);

  // Each ping draws from its own stream: the same bytes whatever the thread count.
  std::vector<std::vector<Beam>> beams_per_ping(ping_steps.size());
#pragma omp parallel for schedule(dynamic, 64)
  for (std::size_t k = 0; k < ping_steps.size(); ++k) {
    const VehicleState& v = states[ping_steps[k]];
    auto rng = make_rng(config.seed, kSonarNoiseStream, k);
    const Eigen::Isometry3d pose = vehicle_pose(
        {v.time, v.x, v.y, v.depth_m, v.roll_deg, v.pitch_deg, v.heading_deg}, LocalOrigin{});
    beams_per_ping[k] = ping(sim.terrain, pose, config.sonar, rng);
  }
  std::size_t total = 0;
  for (const auto& b : beams_per_ping) total += b.size();
  survey.beams.reserve(total);
  for (std::size_t k = 0; k < ping_steps.size(); ++k) {
    survey.pings.push_back({states[ping_steps[k]].time, static_cast<uint32_t>(survey.beams.size()),
                            static_cast<uint32_t>(beams_per_ping[k].size())});
    survey.beams.insert(survey.beams.end(), beams_per_ping[k].begin(), beams_per_ping[k].end());
    std::vector<Beam>().swap(beams_per_ping[k]);
  }

  if (config.drift == DriftModel::kPaper) {
    PaperDrift drift = config.paper_drift;
    if (drift.sigma_yaw_rad <= 0) drift.sigma_yaw_rad = calibrated_paper_sigma_yaw();
    sim.sigma_yaw_rad = drift.sigma_yaw_rad;
    survey.nav = apply_paper_drift(truth, survey.pings.front().time, drift, config.seed);
  } else {
    survey.nav = apply_dvl_drift(truth, config.dvl_drift, config.seed);
  }
  sim.drift = drift_stats(survey.nav, truth);
  survey.reference_nav = std::move(truth);

  const SonarConfig& s = config.sonar;
  survey.metadata.sonar = {{"model", "simulated multibeam"},
                           {"beams", s.beams},
                           {"swath_deg", s.swath_deg},
                           {"ping_rate_hz", s.ping_rate_hz},
                           {"range_noise", {{"base_m", s.noise_base_m},
                                            {"depth_fraction", s.noise_depth_fraction}}}};
  nlohmann::json drift_json = {{"model", to_string(config.drift)}, {"seed", config.seed}};
  if (config.drift == DriftModel::kPaper) {
    drift_json["sigma_translation_m"] = config.paper_drift.sigma_translation_m;
    drift_json["sigma_yaw_rad"] = sim.sigma_yaw_rad;
  } else {
    drift_json["scale_sigma"] = config.dvl_drift.scale_sigma;
    drift_json["heading_bias_sigma_rad"] = config.dvl_drift.heading_bias_sigma_rad;
    drift_json["heading_bias_walk_rad_per_sqrt_s"] = config.dvl_drift.heading_bias_walk_rad_per_sqrt_s;
    drift_json["velocity_noise_m_s"] = config.dvl_drift.velocity_noise_m_s;
  }
  survey.metadata.vehicle = {{"model", "simulated AUV"},
                             {"speed_m_s", motion.speed_m_s},
                             {"depth_m", motion.vehicle_depth_m},
                             {"navigation", "dead reckoning (simulated drift)"},
                             {"simulation", {{"scenario", to_string(config.scenario)},
                                             {"seed", config.seed},
                                             {"drift", drift_json}}}};
  return sim;
}

}  // namespace bathyslam::sim
