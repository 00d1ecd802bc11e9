#include "core/sim/simulator.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "core/sim/random.h"
#include "core/sim/site.h"

#include <Eigen/Geometry>
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

// A survey's name says how it differs from its scenario's default: terrain and line spacing
// appear only when not the default, so default surveys keep their names.
std::string survey_name(const SimulationConfig& config, double line_spacing_m) {
  std::string name = to_string(config.scenario) + "-seed" + std::to_string(config.seed) + "-" +
                     to_string(config.drift);
  if (config.terrain.kind != TerrainKind::kLake) name += "-" + to_string(config.terrain.kind);
  if (line_spacing_m != default_line_spacing_m(config.scenario)) {
    char spacing[32];
    std::snprintf(spacing, sizeof spacing, "-spacing%gm", line_spacing_m);
    name += spacing;
  }
  if (config.altitude_m) {
    char altitude[32];
    std::snprintf(altitude, sizeof altitude, "-altitude%gm", *config.altitude_m);
    name += altitude;
  }
  if (config.epoch > 0) name += "-epoch" + std::to_string(config.epoch);
  return name;
}

nlohmann::json terrain_json(const TerrainConfig& terrain) {
  nlohmann::json json = {{"kind", to_string(terrain.kind)}};
  if (terrain.sand_wavelength_fixed_m) json["sand_wavelength_m"] = *terrain.sand_wavelength_fixed_m;
  if (terrain.sand_crest_angle_fixed_deg) json["sand_crest_angle_deg"] = *terrain.sand_crest_angle_fixed_deg;
  return json;
}

nlohmann::json dvl_json(const DvlDrift& drift) {
  return {{"scale_sigma", drift.scale_sigma},
          {"heading_bias_sigma_rad", drift.heading_bias_sigma_rad},
          {"heading_bias_walk_rad_per_sqrt_s", drift.heading_bias_walk_rad_per_sqrt_s},
          {"velocity_noise_m_s", drift.velocity_noise_m_s}};
}

// The drift model's parameters, and a compass fault's time and size: what the bundle's dead
// reckoning was made with.
nlohmann::json drift_json(const SimulationConfig& config, const Simulation& sim) {
  nlohmann::json json = {{"model", to_string(config.drift)}, {"seed", config.seed}};
  switch (config.drift) {
    case DriftModel::kPaper:
      json["sigma_translation_m"] = sim.sigma_translation_m;
      json["sigma_yaw_rad"] = sim.sigma_yaw_rad;
      break;
    case DriftModel::kDvl: json.update(dvl_json(config.dvl_drift)); break;
    case DriftModel::kHeadingWalk: json.update(dvl_json(config.heading_walk_drift)); break;
    case DriftModel::kCompassStep: {
      const CompassStepDrift& d = config.compass_step_drift;
      json.update(dvl_json(d.dvl));
      json["compass_step"] = {{"min_step_deg", d.min_step_deg},
                              {"max_step_deg", d.max_step_deg},
                              {"earliest_fraction", d.earliest},
                              {"latest_fraction", d.latest},
                              {"time", sim.compass_step->time},
                              {"step_deg", sim.compass_step->step_rad * 180.0 / M_PI}};
      break;
    }
  }
  return json;
}

// The scenario's sonar height: its mean depth less the vehicle's.
double default_altitude_m(const SimulationConfig& config) {
  return config.terrain.mean_depth_m - config.motion.vehicle_depth_m;
}

double world_scale(const SimulationConfig& config) {
  return config.altitude_m ? *config.altitude_m / default_altitude_m(config) : 1.0;
}

// The sonar flown at the configured altitude: its range stretched with the world, its pings no
// faster than their echoes.
SonarConfig sonar_of(const SimulationConfig& config) {
  SonarConfig sonar = config.sonar;
  if (!config.altitude_m) return sonar;
  sonar.max_range_m *= world_scale(config);
  const double fastest_hz = echo_limited_ping_rate_hz(*config.altitude_m, sonar.swath_deg);
  if (fastest_hz < sonar.ping_rate_hz) {
    // Pings fall on the simulation's steps: the interval is a whole number of them.
    const double step_s = config.motion.step_s;
    sonar.ping_rate_hz = 1 / (step_s * std::ceil(1 / (fastest_hz * step_s) - 1e-9));
  }
  return sonar;
}

// Dead reckoning from the truth by the configured model; records what the model drew. `sonar`
// is the one flown (sonar_of). At another altitude the world is larger and a submap of the same
// pings takes longer, so there are more submap steps than in the scenario; the paper model's
// per-step noise is shrunk so that the drift at the end is the world's scale times the
// scenario's: the same error for the survey's size.
std::vector<NavSample> dead_reckoning(const SimulationConfig& config, const SonarConfig& sonar,
                                      const std::vector<NavSample>& truth, double first_ping_time,
                                      Simulation& sim) {
  switch (config.drift) {
    case DriftModel::kPaper: {
      const double scale = world_scale(config);
      const double steps_scale = scale * sonar.ping_rate_hz / config.sonar.ping_rate_hz;
      PaperDrift drift = config.paper_drift;
      if (drift.sigma_yaw_rad <= 0) drift.sigma_yaw_rad = calibrated_paper_sigma_yaw();
      drift.sigma_yaw_rad /= std::sqrt(steps_scale);
      drift.sigma_translation_m *= scale / std::sqrt(steps_scale);
      drift.submap_duration_s *= config.sonar.ping_rate_hz / sonar.ping_rate_hz;
      sim.sigma_yaw_rad = drift.sigma_yaw_rad;
      sim.sigma_translation_m = drift.sigma_translation_m;
      return apply_paper_drift(truth, first_ping_time, drift, config.seed);
    }
    case DriftModel::kDvl: return apply_dvl_drift(truth, config.dvl_drift, config.seed);
    case DriftModel::kHeadingWalk: return apply_dvl_drift(truth, config.heading_walk_drift, config.seed);
    case DriftModel::kCompassStep:
      sim.compass_step = draw_compass_step(truth, config.compass_step_drift, config.seed);
      return apply_dvl_drift(truth, config.compass_step_drift.dvl, config.seed, sim.compass_step);
  }
  throw std::invalid_argument("unknown drift model");
}

}  // namespace

DriftModel parse_drift_model(const std::string& name) {
  for (DriftModel model : {DriftModel::kPaper, DriftModel::kDvl, DriftModel::kHeadingWalk,
                           DriftModel::kCompassStep}) {
    if (to_string(model) == name) return model;
  }
  throw std::invalid_argument("unknown drift model '" + name +
                              "' (expected paper, dvl, heading-walk or compass-step)");
}

std::string to_string(DriftModel model) {
  switch (model) {
    case DriftModel::kPaper: return "paper";
    case DriftModel::kDvl: return "dvl";
    case DriftModel::kHeadingWalk: return "heading-walk";
    case DriftModel::kCompassStep: return "compass-step";
  }
  return "?";
}

double echo_limited_ping_rate_hz(double altitude_m, double swath_deg) {
  const double slant_range_m = altitude_m / std::cos(swath_deg / 2 * M_PI / 180);
  return 1500.0 / (2 * slant_range_m);
}

namespace {

// A later epoch's own randomness (motion, sonar noise, drift) from the site's seed; the seabed
// keeps the site's.
uint64_t epoch_seed(const SimulationConfig& config) {
  return config.epoch > 1 ? mix_seed(config.seed ^ (static_cast<uint64_t>(config.epoch) << 32)) : config.seed;
}

// Dead reckoning that began where the start fix put the vehicle: turned about its first sample
// and moved by `error` (x, y in m; heading in rad, counter-clockwise).
void start_from_fix(std::vector<NavSample>& nav, const Eigen::Vector3d& error) {
  if (nav.empty() || error.isZero()) return;
  const Eigen::Vector2d first(nav.front().easting, nav.front().northing);
  const Eigen::Rotation2Dd turn(error.z());
  for (NavSample& n : nav) {
    const Eigen::Vector2d p = first + turn * (Eigen::Vector2d(n.easting, n.northing) - first) + error.head<2>();
    n.easting = p.x();
    n.northing = p.y();
    n.heading_deg = std::fmod(n.heading_deg - error.z() * 180.0 / M_PI + 360.0, 360.0);
  }
}

// `after` less `before` at the centres of the global cells of `cell_m` over `area` (map frame,
// `e0`, `n0` its origin in the CRS).
ChangeGrid change_since(const Terrain& before, const Terrain& after, const Area& area, double cell_m, double e0, double n0) {
  ChangeGrid g;
  g.cell_m = cell_m;
  g.left = static_cast<std::int64_t>(std::floor((e0 + area.min.x()) / cell_m));
  g.top = static_cast<std::int64_t>(std::floor((n0 + area.max.y()) / cell_m));
  g.cols = static_cast<int>(static_cast<std::int64_t>(std::floor((e0 + area.max.x()) / cell_m)) - g.left + 1);
  g.rows = static_cast<int>(g.top - static_cast<std::int64_t>(std::floor((n0 + area.min.y()) / cell_m)) + 1);
  g.change.resize(static_cast<std::size_t>(g.cols) * static_cast<std::size_t>(g.rows));
  for (int r = 0; r < g.rows; ++r) {
    const double y = (static_cast<double>(g.top - r) + 0.5) * cell_m - n0;
    for (int c = 0; c < g.cols; ++c) {
      const double x = (static_cast<double>(g.left + c) + 0.5) * cell_m - e0;
      g.change[static_cast<std::size_t>(r) * g.cols + c] = static_cast<float>(after.elevation(x, y) - before.elevation(x, y));
    }
  }
  return g;
}

}  // namespace

Simulation simulate(const SimulationConfig& given) {
  Survey kept;
  Simulation sim = simulate(given, [&](double time, std::span<const Beam> beams) {
    // Pings index their beams in 32 bits: a survey of more is simulated streamed only.
    if (kept.beams.size() + beams.size() > std::numeric_limits<uint32_t>::max())
      throw std::length_error("a survey of more than 2^32 soundings cannot be held whole: simulate it streamed");
    kept.pings.push_back({time, static_cast<uint32_t>(kept.beams.size()), static_cast<uint32_t>(beams.size())});
    kept.beams.insert(kept.beams.end(), beams.begin(), beams.end());
  });
  sim.survey.pings = std::move(kept.pings);
  sim.survey.beams = std::move(kept.beams);
  return sim;
}

Simulation simulate(const SimulationConfig& given, const PingSink& sink) {
  SimulationConfig config = given;
  config.seed = epoch_seed(given);
  MotionConfig motion = config.motion;
  motion.seed = config.seed;
  TerrainConfig terrain_config = config.terrain;
  terrain_config.seed = given.seed;
  // In the terrain's own units: Terrain::generate stretches it by the scale with the rest.
  if (config.epoch > 1) terrain_config.sand_migration_m = (config.epoch - 1) * config.sand_migration_per_epoch_m;
  const double k = world_scale(config);
  const SonarConfig sonar = sonar_of(config);
  motion.vehicle_depth_m *= k;
  motion.run_in_m *= k;

  const double line_spacing_m =
      config.line_spacing_m.value_or(default_line_spacing_m(config.scenario));
  motion.turn_radius_m = k * lawnmower_turn_radius_m(line_spacing_m);
  std::vector<LineSpec> lines = survey_pattern(config.scenario, line_spacing_m);
  for (LineSpec& line : lines) line = {k * line.start, k * line.end};
  // Half a swath either side of the lines, plus room for turns.
  const double margin = k * (40.0 + 2.0 * terrain_config.mean_depth_m);
  const Area seabed_area = config.epoch > 0 ? site_area(lines, k * line_spacing_m, margin) : pattern_area(lines, margin);
  const std::vector<SeabedChange> changes = config.epoch > 1 ? seabed_changes(pattern_area(lines, 0), k) : std::vector<SeabedChange>{};
  if (config.epoch > 1) {
    lines = epoch_lines(lines, config.epoch, k * line_spacing_m);
    motion.start_time += (config.epoch - 1) * 30 * 86400.0;  // a month apart
  }
  const std::vector<VehicleState> states = drive(lines, motion);
  Simulation sim;
  sim.terrain = Terrain::generate(terrain_config, seabed_area, k);
  for (const SeabedChange& change : changes) {
    sim.terrain.change([&](double x, double y) { return elevation_change(change, x, y); });
  }
  if (config.epoch > 1) {
    TerrainConfig first = terrain_config;
    first.sand_migration_m = 0;
    sim.truth_change = change_since(Terrain::generate(first, seabed_area, k), sim.terrain, seabed_area, 0.5 * k,
                                    config.origin_easting, config.origin_northing);
  }

  Survey& survey = sim.survey;
  survey.metadata.name = survey_name(given, line_spacing_m);
  survey.metadata.crs = config.crs;

  // Navigation at its rate from the first step; pings at theirs, offset by one step so ping
  // times fall between navigation samples and the sync stage really interpolates.
  const std::size_t nav_stride = steps_per(1.0 / config.nav_rate_hz, motion.step_s);
  const std::size_t ping_stride = steps_per(1.0 / sonar.ping_rate_hz, motion.step_s);
  const std::size_t lead = steps_per(kNavLeadS, motion.step_s);
  std::vector<NavSample> truth =
      navigation_of(states, nav_stride, config.origin_easting, config.origin_northing);
  std::vector<std::size_t> ping_steps;
  for (std::size_t i = lead + 1; i + lead < states.size(); i += ping_stride) ping_steps.push_back(i);
  if (ping_steps.empty()) throw std::invalid_argument("the survey pattern is too short for a single ping");

  // Each ping draws from its own stream: the same bytes whatever the thread count. Made a block
  // at a time, in parallel within it, and given to the sink in order.
  constexpr std::size_t kBlock = 4096;
  std::vector<std::vector<Beam>> beams_per_ping(kBlock);
  for (std::size_t first = 0; first < ping_steps.size(); first += kBlock) {
    const std::size_t count = std::min(kBlock, ping_steps.size() - first);
#pragma omp parallel for schedule(dynamic, 64)
    for (std::size_t j = 0; j < count; ++j) {
      const std::size_t k = first + j;
      const VehicleState& v = states[ping_steps[k]];
      auto rng = make_rng(config.seed, kSonarNoiseStream, k);
      const Eigen::Isometry3d pose = vehicle_pose(
          {v.time, v.x, v.y, v.depth_m, v.roll_deg, v.pitch_deg, v.heading_deg}, LocalOrigin{});
      beams_per_ping[j] = ping(sim.terrain, pose, sonar, rng);
    }
    for (std::size_t j = 0; j < count; ++j) sink(states[ping_steps[first + j]].time, beams_per_ping[j]);
  }

  survey.nav = dead_reckoning(config, sonar, truth, states[ping_steps.front()].time, sim);
  start_from_fix(survey.nav, start_fix_error(given.seed, config.epoch));
  sim.drift = drift_stats(survey.nav, truth);
  survey.reference_nav = std::move(truth);

  const SonarConfig& s = sonar;
  survey.metadata.sonar = {{"model", "simulated multibeam"},
                           {"beams", s.beams},
                           {"swath_deg", s.swath_deg},
                           {"ping_rate_hz", s.ping_rate_hz},
                           {"range_noise", {{"base_m", s.noise_base_m},
                                            {"depth_fraction", s.noise_depth_fraction}}}};
  survey.metadata.vehicle = {{"model", "simulated AUV"},
                             {"speed_m_s", motion.speed_m_s},
                             {"depth_m", motion.vehicle_depth_m},
                             {"navigation", "dead reckoning (simulated drift)"},
                             {"simulation", {{"scenario", to_string(config.scenario)},
                                             {"seed", config.seed},
                                             {"drift", drift_json(config, sim)}}}};
  // Recorded when not the default, as in the name, so default surveys keep their bytes.
  nlohmann::json& simulation = survey.metadata.vehicle["simulation"];
  if (config.terrain.kind != TerrainKind::kLake) simulation["terrain"] = terrain_json(config.terrain);
  if (line_spacing_m != default_line_spacing_m(config.scenario)) {
    simulation["line_spacing_m"] = line_spacing_m;
    simulation["turn_radius_m"] = motion.turn_radius_m;
  }
  if (config.altitude_m) simulation["altitude_m"] = *config.altitude_m;
  if (config.epoch > 0) {
    const Eigen::Vector3d fix = start_fix_error(given.seed, config.epoch);
    simulation["site"] = {{"seed", given.seed}, {"epoch", config.epoch},
                          {"start_fix_error", {{"x_m", fix.x()}, {"y_m", fix.y()}, {"heading_rad", fix.z()}}},
                          {"changes_since_epoch_1", nlohmann::json::array()},
                          {"local_origin", {{"easting", config.origin_easting}, {"northing", config.origin_northing}}}};
    for (const SeabedChange& change : changes) simulation["site"]["changes_since_epoch_1"].push_back(to_json(change));
    const bool sand_waves = config.terrain.kind == TerrainKind::kSandWaves || config.terrain.kind == TerrainKind::kMixed;
    if (config.epoch > 1 && sand_waves) simulation["site"]["sand_waves_migrated_m"] = k * terrain_config.sand_migration_m;
  }
  return sim;
}

}  // namespace bathyslam::sim
