#include <array>
#include <chrono>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "client/commands.h"
#include "core/io/bundle.h"
#include "core/io/gsf/gsf_survey.h"
#include "core/sim/simulator.h"
#include "core/tiles/geotiff_writer.h"

namespace bathyslam::cli {
namespace {

struct SimulateOptions {
  std::string scenario = "small";
  uint64_t seed = 1;
  std::string drift = "paper";
  double sigma_yaw_rad = 0;
  std::string terrain = "lake";
  std::optional<double> line_spacing_m;
  std::optional<double> altitude_m;
  std::optional<double> wavelength_m;
  std::optional<double> wave_angle_deg;
  int epoch = 0;
  double sand_migration_m = sim::kSandMigrationPerEpochM;
  std::optional<int> beams;
  std::optional<double> swath_deg;
  std::string format = "bundle";
  std::string out;
};

// GSF: the pings with the dead-reckoning navigation in <out>/survey.gsf, and the truth beside it
// in <out>/reference_nav.csv (GSF has no record for a second trajectory).
std::string write_gsf_survey(const Survey& survey, const std::filesystem::path& out) {
  std::filesystem::create_directories(out);
  const std::uint64_t pings = gsf::write_survey(survey, survey.nav, out / "survey.gsf");
  std::string written = (out / "survey.gsf").string() + " (" + std::to_string(pings) + " pings)";
  if (survey.reference_nav) {
    write_nav_csv(*survey.reference_nav, out / "reference_nav.csv");
    written += " and reference_nav.csv";
  }
  return written;
}

void print_drift_model(const sim::SimulationConfig& config, const sim::Simulation& simulation,
                       bool sigma_yaw_given) {
  switch (config.drift) {
    case sim::DriftModel::kPaper:
      std::printf("  drift: paper model, sigma_t = %.3f m, sigma_yaw = %.3g rad per submap%s\n",
                  simulation.sigma_translation_m, simulation.sigma_yaw_rad,
                  sigma_yaw_given ? " (given)"
                  : config.altitude_m ? " (calibrated: mean DR error 17.5 m over lake, scaled with the altitude)"
                                      : " (calibrated: mean DR error 17.5 m over lake)");
      break;
    case sim::DriftModel::kDvl:
      std::printf("  drift: dvl model, ~0.3 %% of distance along a line\n");
      break;
    case sim::DriftModel::kHeadingWalk:
      std::printf("  drift: heading-walk model, heading bias walk %.3g rad/sqrt(s)\n",
                  config.heading_walk_drift.heading_bias_walk_rad_per_sqrt_s);
      break;
    case sim::DriftModel::kCompassStep:
      std::printf("  drift: compass-step model, heading steps %+.2f deg at t = %.3f\n",
                  simulation.compass_step->step_rad * 180.0 / M_PI, simulation.compass_step->time);
      break;
  }
}

// A later epoch's true change since epoch 1 as truth_change.tif (one Float32 band "change"), the
// answer a site's difference maps are scored against: not part of the survey.
void write_truth_change(const sim::ChangeGrid& truth, const std::string& crs, const std::string& out) {
  const GridGeometry geometry{.resolution_m = truth.cell_m, .left = truth.left, .top = truth.top, .width = truth.cols,
                              .height = truth.rows};
  const std::array<NamedBand, 1> bands{{{"change", &truth.change}}};
  write_geotiff(geometry, bands, crs, std::filesystem::path(out) / "truth_change.tif");
}

void run_simulate(const SimulateOptions& o) {
  sim::SimulationConfig config;
  config.scenario = sim::parse_scenario(o.scenario);
  config.seed = o.seed;
  config.drift = sim::parse_drift_model(o.drift);
  config.paper_drift.sigma_yaw_rad = o.sigma_yaw_rad;
  config.terrain.kind = sim::parse_terrain_kind(o.terrain);
  config.terrain.sand_wavelength_fixed_m = o.wavelength_m;
  config.terrain.sand_crest_angle_fixed_deg = o.wave_angle_deg;
  config.line_spacing_m = o.line_spacing_m;
  config.altitude_m = o.altitude_m;
  config.epoch = o.epoch;
  config.sand_migration_per_epoch_m = o.sand_migration_m;
  if (o.beams) config.sonar.beams = *o.beams;
  if (o.swath_deg) config.sonar.swath_deg = *o.swath_deg;

  const auto start = std::chrono::steady_clock::now();
  // A bundle is written as the pings are made, so that a survey of any length simulates in the
  // memory of a few thousand pings; GSF out holds the survey whole.
  std::optional<sim::Simulation> made;
  std::size_t pings_made = 0, soundings = 0;
  const bool bundle = o.format != "gsf";
  if (bundle) {
    std::filesystem::create_directories(o.out);
    PingsCsvWriter pings(std::filesystem::path(o.out) / kPingsFile);
    made = sim::simulate(config, [&](double time, std::span<const Beam> beams) {
      pings.add(time, beams);
      ++pings_made;
      soundings += beams.size();
    });
    pings.commit();
  } else {
    made = sim::simulate(config);
    std::printf("wrote %s\n", write_gsf_survey(made->survey, o.out).c_str());
    pings_made = made->survey.pings.size();
    soundings = made->survey.beams.size();
  }
  const sim::Simulation& simulation = *made;
  if (simulation.truth_change) write_truth_change(*simulation.truth_change, simulation.survey.metadata.crs, o.out);
  if (bundle) write_bundle_without_pings(simulation.survey, o.out);  // survey.json last: the bundle is whole
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const Survey& s = simulation.survey;
  std::printf("simulated %s (seed %llu) in %.1f s -> %s\n", o.scenario.c_str(),
              static_cast<unsigned long long>(o.seed), seconds, o.out.c_str());
  if (o.terrain != "lake" || o.line_spacing_m) {
    std::printf("  terrain %s, line spacing %g m\n", o.terrain.c_str(),
                o.line_spacing_m.value_or(sim::default_line_spacing_m(config.scenario)));
  }
  if (o.altitude_m) {
    std::printf("  altitude %g m, %g pings a second\n", *o.altitude_m, s.metadata.sonar.value("ping_rate_hz", 0.0));
  }
  std::printf("  %zu pings, %zu soundings, %zu navigation samples\n", pings_made, soundings, s.nav.size());
  if (o.epoch > 0) {
    const auto& site = s.metadata.vehicle["simulation"]["site"];
    std::printf("  epoch %d of the site of seed %llu: start fix off by (%.2f, %.2f) m and %.2f deg, %zu seabed changes since epoch 1\n",
                o.epoch, static_cast<unsigned long long>(o.seed), site["start_fix_error"]["x_m"].get<double>(),
                site["start_fix_error"]["y_m"].get<double>(), site["start_fix_error"]["heading_rad"].get<double>() * 180 / M_PI,
                site["changes_since_epoch_1"].size());
  }
  print_drift_model(config, simulation, o.sigma_yaw_rad > 0);
  std::printf("  DR error: mean %.2f m, rms %.2f m, max %.2f m, end %.2f m over %.0f m travelled\n",
              simulation.drift.mean_m, simulation.drift.rms_m, simulation.drift.max_m,
              simulation.drift.end_m, simulation.drift.distance_travelled_m);
}

}  // namespace

void add_simulate_command(CLI::App& app) {
  auto options = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand("simulate", "Simulate a survey bundle with known truth");
  cmd->add_option("--scenario", options->scenario, "small, lake, large or xlarge (four times large)")
      ->check(CLI::IsMember({"small", "lake", "large", "xlarge"}))
      ->capture_default_str();
  cmd->add_option("--seed", options->seed, "random seed (same seed, same bytes)")
      ->capture_default_str();
  cmd->add_option("--drift", options->drift,
                  "dead-reckoning drift model: paper, dvl, heading-walk or compass-step")
      ->check(CLI::IsMember({"paper", "dvl", "heading-walk", "compass-step"}))
      ->capture_default_str();
  cmd->add_option("--terrain", options->terrain,
                  "seabed: lake, sandwaves, boulders, channel, slopebreak, flat or mixed")
      ->check(CLI::IsMember({"lake", "sandwaves", "boulders", "channel", "slopebreak", "flat", "mixed"}))
      ->capture_default_str();
  cmd->add_option("--line-spacing", options->line_spacing_m,
                  "metres between lawnmower lines (default: the scenario's 30 m)")
      ->check(CLI::Range(5.0, 200.0));
  cmd->add_option("--altitude", options->altitude_m,
                  "sonar height above the seabed in m (default: the scenario's 9 m); the seabed, lines and "
                  "drift scale with it, the ping rate falls as the echoes take longer")
      ->check(CLI::Range(1.0, 5000.0));
  cmd->add_option("--wavelength", options->wavelength_m,
                  "sandwaves: the dominant wavelength in m (default: drawn from 8-40 m)")
      ->check(CLI::Range(2.0, 200.0));
  cmd->add_option("--wave-angle", options->wave_angle_deg,
                  "sandwaves: crest direction in degrees counter-clockwise from east "
                  "(default: drawn 20-70 deg either side of east)")
      ->check(CLI::Range(-180.0, 180.0));
  cmd->add_option("--sigma-yaw", options->sigma_yaw_rad,
                  "paper model: yaw noise per submap in rad (default: calibrated)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--epoch", options->epoch,
                  "the site's k-th survey (1, 2, ...): the same seabed, changed after epoch 1, flown on other lines with "
                  "its own drift and start fix; 0: a survey alone")
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--sand-migration", options->sand_migration_m,
                  "a later epoch: how far sand waves (sandwaves, mixed) moved across their crests per epoch, in m at the "
                  "lake's scale")
      ->check(CLI::Range(0.0, 100.0))
      ->capture_default_str();
  cmd->add_option("--beams", options->beams, "the sonar's beams (512): another vehicle's sonar")->check(CLI::Range(16, 4096));
  cmd->add_option("--swath", options->swath_deg, "the sonar's swath in degrees (140)")->check(CLI::Range(10.0, 170.0));
  cmd->add_option("--format", options->format,
                  "bundle (nav.csv, pings.csv, ...) or gsf (survey.gsf and reference_nav.csv)")
      ->check(CLI::IsMember({"bundle", "gsf"}))
      ->capture_default_str();
  cmd->add_option("--out", options->out, "folder to write")->required();
  cmd->callback([options] { run_simulate(*options); });
}

}  // namespace bathyslam::cli
