#pragma once
// `bathyslam simulate`: a survey with known truth, deterministic from its seed.
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>

#include "core/sim/drift.h"
#include "core/sim/site.h"
#include "core/sim/sonar.h"
#include "core/sim/terrain.h"
#include "core/sim/trajectory.h"
#include "core/types/survey.h"

namespace bathyslam::sim {

enum class DriftModel { kPaper, kDvl, kHeadingWalk, kCompassStep };
DriftModel parse_drift_model(const std::string& name);  // throws std::invalid_argument
std::string to_string(DriftModel model);

struct SimulationConfig {
  Scenario scenario = Scenario::kSmall;
  uint64_t seed = 1;
  DriftModel drift = DriftModel::kPaper;
  PaperDrift paper_drift;
  DvlDrift dvl_drift;
  DvlDrift heading_walk_drift = make_heading_walk_drift();
  CompassStepDrift compass_step_drift;
  TerrainConfig terrain;  // its seed is replaced by `seed`
  std::optional<double> line_spacing_m;  // the scenario's when unset
  // The sonar's height above the mean seabed; the scenario's (9 m) when unset. The whole world
  // scales with it (the seabed in every direction, the lines, the turns, the sonar's range and
  // the paper drift's error), as a survey of the same site flown higher would see a larger one;
  // the vehicle keeps its speed and the sonar its fan, pinging as fast as the outer beams' echoes
  // come back (at most its ping rate).
  std::optional<double> altitude_m;
  // 0: a survey alone. k >= 1: the k-th survey of a site (site.h): the seabed of `seed` over the
  // site's area, changed after epoch 1; the pattern, drift, sonar noise and start fix of epoch k.
  int epoch = 0;
  // A later epoch's sand waves (sandwaves, mixed) have moved this far across their crests per
  // epoch since the first, at the lake's scale (site.h).
  double sand_migration_per_epoch_m = kSandMigrationPerEpochM;
  MotionConfig motion;    // its seed is replaced by `seed`
  SonarConfig sonar;
  double nav_rate_hz = 20.0;
  std::string crs = "EPSG:32651";  // UTM 51N, where the paper's lake lies
  double origin_easting = 452000.0;
  double origin_northing = 4630000.0;
};

// A later epoch of a site: the seabed's true change since epoch 1 (elevation, m; every change of
// site.h, sand waves' migration included), at cell centres of a grid of global CRS cells as
// core/fuse/grid.h's GridGeometry counts them (column `left` from the west, row `top` the
// northernmost, rows north first), for scoring difference maps (bench_change_detection).
struct ChangeGrid {
  double cell_m = 0;
  std::int64_t left = 0, top = 0;
  int cols = 0, rows = 0;
  std::vector<float> change;
};

struct Simulation {
  Survey survey;  // nav = dead reckoning, reference_nav = truth
  Terrain terrain;
  std::optional<ChangeGrid> truth_change;  // epochs after the first
  double sigma_yaw_rad = 0;  // the paper model's sigma_yaw used (0 for the others)
  double sigma_translation_m = 0;  // and its sigma_translation
  std::optional<HeadingStep> compass_step;  // the compass-step model's fault
  DriftStats drift;
};

Simulation simulate(const SimulationConfig& config);

// The same with each ping given to `sink` in time order as it is made, and none kept in the
// survey (its `pings` and `beams` stay empty): the pings take the memory of a few thousand
// however long the survey (the seabed grid still grows with its area). The pings, their beams
// and every other field are those simulate() gives.
using PingSink = std::function<void(double time, std::span<const Beam> beams)>;
Simulation simulate(const SimulationConfig& config, const PingSink& sink);

// The fastest a sonar can ping when the echo of its outermost beam must be back first: two slant
// ranges at 1500 m/s.
double echo_limited_ping_rate_hz(double altitude_m, double swath_deg);

}  // namespace bathyslam::sim
