#include "core/sim/simulator.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "core/io/bundle.h"

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

TEST_F(SmallScenario, BundleReadsBackValid) {
  const fs::path dir = fs::temp_directory_path() / "bathyslam_sim_valid";
  write_bundle(simulation_->survey, dir);
  const BundleReadResult result = read_bundle(dir);
  EXPECT_TRUE(result.survey);
  EXPECT_TRUE(result.problems.empty()) << result.problems.front().to_string();
  fs::remove_all(dir);
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

}  // namespace
}  // namespace bathyslam::sim
