#include "core/sim/simulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/io/bundle.h"
#include "core/sim/site.h"

namespace bathyslam::sim {
namespace {

namespace fs = std::filesystem;

std::string file_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class SmallScenario : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    SimulationConfig config;
    config.seed = 11;
    simulation_ = new Simulation(simulate(config));
  }
  static void TearDownTestSuite() { delete simulation_; }
  static Simulation* simulation_;
};
Simulation* SmallScenario::simulation_ = nullptr;

TEST_F(SmallScenario, HasTheSonarAndRatesOfTheDesign) {
  const Survey& s = simulation_->survey;
  ASSERT_GT(s.pings.size(), 2500u);
  // 10 pings/s.
  const double span = s.pings.back().time - s.pings.front().time;
  EXPECT_NEAR((s.pings.size() - 1) / span, 10.0, 1e-6);
  // Every beam of every ping finds the bottom at 10 m.
  EXPECT_EQ(s.beams.size(), s.pings.size() * 512);
  // Pings lie inside the navigation.
  EXPECT_GT(s.pings.front().time, s.nav.front().time);
  EXPECT_LT(s.pings.back().time, s.nav.back().time);
  ASSERT_TRUE(s.reference_nav);
  EXPECT_EQ(s.reference_nav->size(), s.nav.size());
}

TEST_F(SmallScenario, SameSeedSameBytesDifferentSeedDifferentSurvey) {
  const fs::path a = fs::temp_directory_path() / "bathyslam_sim_a";
  const fs::path b = fs::temp_directory_path() / "bathyslam_sim_b";
  const fs::path c = fs::temp_directory_path() / "bathyslam_sim_c";
  SimulationConfig config;
  config.seed = 11;
  write_bundle(simulation_->survey, a);
  write_bundle(simulate(config).survey, b);
  config.seed = 12;
  write_bundle(simulate(config).survey, c);
  for (auto file : {kSurveyJsonFile, kNavFile, kPingsFile, kReferenceNavFile}) {
    EXPECT_EQ(file_bytes(a / file), file_bytes(b / file)) << file << " differs for the same seed";
  }
  EXPECT_NE(file_bytes(a / kPingsFile), file_bytes(c / kPingsFile));
  EXPECT_NE(file_bytes(a / kNavFile), file_bytes(c / kNavFile));
  for (const auto& d : {a, b, c}) fs::remove_all(d);
}

// `bathyslam simulate` streams: each ping goes to the sink in time order as it is made (the small
// survey spans two blocks of pings), the survey keeps none, and the bundle written ping by ping
// is the bundle of the survey made whole, byte for byte.
TEST_F(SmallScenario, StreamedPingsMakeTheSameBundleAndAreNotKept) {
  const fs::path whole = fs::temp_directory_path() / "bathyslam_sim_whole";
  const fs::path streamed = fs::temp_directory_path() / "bathyslam_sim_streamed";
  write_bundle(simulation_->survey, whole);
  fs::create_directories(streamed);
  SimulationConfig config;
  config.seed = 11;
  std::size_t pings = 0;
  double last_time = -INFINITY;
  bool in_order = true;
  PingsCsvWriter writer(streamed / kPingsFile);
  const Simulation made = simulate(config, [&](double time, std::span<const Beam> beams) {
    in_order = in_order && time > last_time;
    last_time = time;
    ++pings;
    writer.add(time, beams);
  });
  writer.commit();
  write_bundle_without_pings(made.survey, streamed);
  EXPECT_TRUE(in_order);
  EXPECT_EQ(pings, simulation_->survey.pings.size());
  EXPECT_GT(pings, 4096u);  // more than one block
  EXPECT_TRUE(made.survey.pings.empty());
  EXPECT_TRUE(made.survey.beams.empty());
  for (auto file : {kSurveyJsonFile, kNavFile, kPingsFile, kReferenceNavFile}) {
    EXPECT_EQ(file_bytes(whole / file), file_bytes(streamed / file)) << file;
  }
  for (const auto& d : {whole, streamed}) fs::remove_all(d);
}

TEST_F(SmallScenario, BundleReadsBackValid) {
  const fs::path dir = fs::temp_directory_path() / "bathyslam_sim_valid";
  write_bundle(simulation_->survey, dir);
  const BundleReadResult result = read_bundle(dir);
  EXPECT_TRUE(result.survey);
  EXPECT_TRUE(result.problems.empty()) << result.problems.front().to_string();
  fs::remove_all(dir);
}

TEST_F(SmallScenario, DefaultSurveyRecordsNoTerrainOrSpacing) {
  // Recorded only when not the default, so default surveys keep their bytes.
  const nlohmann::json& simulation = simulation_->survey.metadata.vehicle["simulation"];
  EXPECT_FALSE(simulation.contains("terrain"));
  EXPECT_FALSE(simulation.contains("line_spacing_m"));
  EXPECT_EQ(simulation_->survey.metadata.name, "small-seed11-paper");
}

TEST(Simulator, DvlDriftModelIsSelectable) {
  SimulationConfig config;
  config.drift = DriftModel::kDvl;
  config.seed = 2;
  const Simulation sim = simulate(config);
  EXPECT_EQ(sim.sigma_yaw_rad, 0.0);
  EXPECT_GT(sim.drift.max_m, 0.05);
  EXPECT_LT(sim.drift.max_m, 0.02 * sim.drift.distance_travelled_m);
  EXPECT_EQ(sim.survey.metadata.vehicle["simulation"]["drift"]["model"], "dvl");
}

TEST(SurveyPattern, OtherLineSpacingsKeepCheckLinesAcrossTheBlockAndDriveTurnsThem) {
  for (double spacing : {20.0, 44.0}) {
    const std::vector<LineSpec> lines = survey_pattern(Scenario::kSmall, spacing);
    ASSERT_EQ(lines.size(), 6u);
    EXPECT_EQ(lines[1].start.y() - lines[0].start.y(), spacing);
    const double block_top = lines[3].start.y();
    for (std::size_t k = 4; k < lines.size(); ++k) {
      EXPECT_LT(std::min(lines[k].start.y(), lines[k].end.y()), 0.0) << "check line " << k;
      EXPECT_GT(std::max(lines[k].start.y(), lines[k].end.y()), block_top) << "check line " << k;
    }
    MotionConfig motion;
    motion.turn_radius_m = lawnmower_turn_radius_m(spacing);
    const std::vector<VehicleState> states = drive(lines, motion);
    const double step_m = motion.speed_m_s * motion.step_s;
    double steepest_turn_deg = 0;
    for (std::size_t i = 1; i < states.size(); ++i) {
      EXPECT_LT(std::hypot(states[i].x - states[i - 1].x, states[i].y - states[i - 1].y), step_m + 1e-6);
      const double turn = std::abs(std::remainder(states[i].heading_deg - states[i - 1].heading_deg, 360.0));
      steepest_turn_deg = std::max(steepest_turn_deg, turn);
    }
    // No tighter than the turn radius: a step of arc turns by step / radius.
    EXPECT_LT(steepest_turn_deg, 1.001 * step_m / motion.turn_radius_m * 180.0 / M_PI);
    // The lawnmower ends where its last line ends: every line was flown.
    EXPECT_NEAR(states.back().x, lines.back().end.x(), step_m);
    EXPECT_NEAR(states.back().y, lines.back().end.y(), step_m);
  }
  EXPECT_EQ(lawnmower_turn_radius_m(30.0), MotionConfig{}.turn_radius_m);
  EXPECT_EQ(lawnmower_turn_radius_m(12.0), 10.0) << "no tighter than the vehicle turns";
}

TEST(Simulator, RecordsTerrainSpacingAndCompassFault) {
  SimulationConfig config;
  config.seed = 4;
  config.terrain.kind = TerrainKind::kSandWaves;
  config.line_spacing_m = 44.0;
  config.drift = DriftModel::kCompassStep;
  config.sonar.beams = 16;  // the metadata is what is tested here
  const Simulation sim = simulate(config);
  EXPECT_EQ(sim.survey.metadata.name, "small-seed4-compass-step-sandwaves-spacing44m");
  const nlohmann::json& simulation = sim.survey.metadata.vehicle["simulation"];
  EXPECT_EQ(simulation["terrain"]["kind"], "sandwaves");
  EXPECT_EQ(simulation["line_spacing_m"], 44.0);
  EXPECT_EQ(simulation["turn_radius_m"], 22.0);
  ASSERT_TRUE(sim.compass_step);
  EXPECT_EQ(simulation["drift"]["compass_step"]["time"], sim.compass_step->time);
  EXPECT_GE(std::abs(simulation["drift"]["compass_step"]["step_deg"].get<double>()), 3.0);
}

// A survey flown higher sees the same seabed scaled with it: the world (seabed, lines, range)
// grows by altitude / 9 m, the pings come no faster than their echoes, and the paper drift's
// error grows with the world. 16 beams: the geometry is what is tested here.
TEST(Simulator, AHigherSurveySeesTheSameSeabedScaledWithIt) {
  SimulationConfig config;
  config.sonar.beams = 16;
  config.terrain.kind = TerrainKind::kBoulders;
  const Simulation low = simulate(config);
  config.altitude_m = 36.0;  // four times the default 9 m
  const Simulation high = simulate(config);
  EXPECT_EQ(high.survey.metadata.name, "small-seed1-paper-boulders-altitude36m");
  EXPECT_EQ(high.survey.metadata.vehicle["simulation"]["altitude_m"], 36.0);
  for (const Eigen::Vector2d p : {Eigen::Vector2d(30, 7), Eigen::Vector2d(101.3, -12.9), Eigen::Vector2d(250, 40)}) {
    EXPECT_NEAR(high.terrain.elevation(4 * p.x(), 4 * p.y()), 4 * low.terrain.elevation(p.x(), p.y()), 1e-3);
  }
  // 36 m below a 140 degree fan: echoes from 105 m slant range, 7.1 Hz, on the 25 ms steps: 6.67 Hz.
  EXPECT_NEAR(echo_limited_ping_rate_hz(36, 140), 7.13, 0.01);
  EXPECT_NEAR(high.survey.metadata.sonar["ping_rate_hz"].get<double>(), 1 / 0.15, 1e-9);
  const double seconds = [](const Survey& s) { return s.pings.back().time - s.pings.front().time; }(high.survey);
  EXPECT_NEAR(seconds / (low.survey.pings.back().time - low.survey.pings.front().time), 4, 0.2) << "same speed, 4x the lines";
  std::vector<float> down;
  for (const Beam& b : high.survey.beams) down.push_back(b.down);
  std::nth_element(down.begin(), down.begin() + down.size() / 2, down.end());
  EXPECT_NEAR(down[down.size() / 2], 36, 1) << "the seabed 36 m below the sonar";
  EXPECT_GT(high.drift.mean_m, 2 * low.drift.mean_m);
}

// Two epochs of one site: the same seabed but where it changed, flown on other lines (other
// headings, another start) with another drift, the second's dead reckoning starting from its start
// fix's error, the first's from the truth (the datum).
TEST(Site, ALaterEpochFliesOtherLinesOverTheSameSeabedChangedWhereItSays) {
  SimulationConfig config;
  config.seed = 4;
  config.epoch = 1;
  const Simulation first = simulate(config);
  config.epoch = 2;
  const Simulation second = simulate(config);
  const auto& site = second.survey.metadata.vehicle["simulation"]["site"];
  ASSERT_EQ(site["changes_since_epoch_1"].size(), 3u);
  std::vector<SeabedChange> changes;
  for (const auto& c : site["changes_since_epoch_1"]) changes.push_back(seabed_change_from_json(c));
  const auto change_at = [&](double x, double y) {
    double sum = 0;
    for (const SeabedChange& c : changes) sum += elevation_change(c, x, y);
    return sum;
  };
  int unchanged = 0, changed = 0;
  for (double x = -20; x < 220; x += 0.9) {
    for (double y = -30; y < 80; y += 0.7) {
      // The terrain is a 0.2 m grid, bilinear between samples: compared where the change is even.
      const double change = change_at(x, y);
      if (std::abs(change_at(x + 0.2, y + 0.2) - change) > 2e-3 || std::abs(change_at(x - 0.2, y - 0.2) - change) > 2e-3) continue;
      EXPECT_NEAR(second.terrain.elevation(x, y) - first.terrain.elevation(x, y), change, 2e-3) << x << ", " << y;
      (change == 0 ? unchanged : changed) += 1;
    }
  }
  EXPECT_GT(changed, 300);
  EXPECT_GT(unchanged, 10000);
  for (const SeabedChange& c : changes) {
    EXPECT_NEAR(second.terrain.elevation(c.centre.x(), c.centre.y()) - first.terrain.elevation(c.centre.x(), c.centre.y()),
                c.height_m, 2e-3) << c.kind;
  }
  // Epoch 1 starts on the truth; epoch 2 as far off as its start fix says, and on another line.
  const NavSample& dr1 = first.survey.nav.front();
  const NavSample& truth1 = first.survey.reference_nav->front();
  EXPECT_NEAR(std::hypot(dr1.easting - truth1.easting, dr1.northing - truth1.northing), 0, 1e-6);
  const NavSample& dr2 = second.survey.nav.front();
  const NavSample& truth2 = second.survey.reference_nav->front();
  EXPECT_NEAR(std::hypot(dr2.easting - truth2.easting, dr2.northing - truth2.northing),
              std::hypot(site["start_fix_error"]["x_m"].get<double>(), site["start_fix_error"]["y_m"].get<double>()), 1e-6);
  EXPECT_GT(std::hypot(truth2.easting - truth1.easting, truth2.northing - truth1.northing), 50);
  EXPECT_GT(std::abs(std::remainder(truth2.heading_deg - truth1.heading_deg, 360.0)), 90);
  EXPECT_NE(second.survey.metadata.name, first.survey.metadata.name);
}

// Sand waves migrate between epochs: the later epoch's truth grid is the two terrains' difference
// at its cells (the migration and the listed changes together), recorded as a distance; with no
// migration the sand waves stay and only the listed changes differ.
TEST(Site, ALaterEpochsSandWavesHaveMigratedAndItsTruthSaysWhere) {
  SimulationConfig config;
  config.seed = 3;
  config.terrain.kind = TerrainKind::kSandWaves;
  config.epoch = 1;
  const Simulation first = simulate(config);
  EXPECT_FALSE(first.truth_change.has_value());
  config.epoch = 2;
  const Simulation moved = simulate(config);
  config.sand_migration_per_epoch_m = 0;
  const Simulation still = simulate(config);
  EXPECT_EQ(moved.survey.metadata.vehicle["simulation"]["site"]["sand_waves_migrated_m"].get<double>(), 2.0);
  ASSERT_TRUE(moved.truth_change.has_value());
  const ChangeGrid& truth = *moved.truth_change;
  const auto& site = moved.survey.metadata.vehicle["simulation"]["site"];
  const double e0 = site["local_origin"]["easting"], n0 = site["local_origin"]["northing"];
  double moved2 = 0, still_max = 0;
  int cells = 0;
  for (int r = 0; r < truth.rows; r += 7) {
    for (int c = 0; c < truth.cols; c += 7) {
      const double x = (static_cast<double>(truth.left + c) + 0.5) * truth.cell_m - e0;
      const double y = (static_cast<double>(truth.top - r) + 0.5) * truth.cell_m - n0;
      const double t = truth.change[static_cast<std::size_t>(r) * truth.cols + c];
      ASSERT_NEAR(t, moved.terrain.elevation(x, y) - first.terrain.elevation(x, y), 1e-4) << x << ", " << y;
      double listed = 0;
      for (const auto& ch : site["changes_since_epoch_1"]) listed += elevation_change(seabed_change_from_json(ch), x, y);
      if (listed != 0) continue;
      moved2 += t * t;
      still_max = std::max(still_max, std::abs(still.terrain.elevation(x, y) - first.terrain.elevation(x, y)));
      ++cells;
    }
  }
  ASSERT_GT(cells, 1000);
  EXPECT_GT(std::sqrt(moved2 / cells), 0.02) << "the sand waves did not move";
  EXPECT_LT(still_max, 1e-4) << "without migration the sand waves stay where they were";
}

// On a mixed seabed only the sand-wave patches move: the others (boulders, channel, slope, flat)
// stay to the float, their mean depth included (a migration once re-centred the whole seabed by
// a fraction of a millimetre).
TEST(Site, OnAMixedSeabedOnlyTheSandWavesMigrate) {
  SimulationConfig config;
  config.seed = 2;
  config.terrain.kind = TerrainKind::kMixed;
  config.epoch = 1;
  const Simulation first = simulate(config);
  config.epoch = 2;
  config.sand_migration_per_epoch_m = 0;
  const Simulation still = simulate(config);
  config.sand_migration_per_epoch_m = 2;
  const Simulation moved = simulate(config);
  int stayed = 0, cells = 0;
  for (double x = -20; x < 220; x += 1.3) {
    for (double y = -30; y < 80; y += 1.1) {
      const double listed = still.terrain.elevation(x, y) - first.terrain.elevation(x, y);
      if (listed != 0) continue;  // the pit, the object, the dredged area
      stayed += std::abs(moved.terrain.elevation(x, y) - first.terrain.elevation(x, y)) < 1e-6;
      ++cells;
    }
  }
  ASSERT_GT(cells, 5000);
  EXPECT_GT(stayed, cells / 3) << "the patches that are not sand waves moved too";
  EXPECT_LT(stayed, cells) << "no sand waves moved";
}

}  // namespace
}  // namespace bathyslam::sim
