#include "core/sim/sonar.h"

#include <gtest/gtest.h>

#include "core/sim/random.h"
#include "core/types/pose.h"

namespace bathyslam::sim {
namespace {

TEST(Sonar, SwathWidthOnFlatBottomIsTwiceAltitudeTimesTan70) {
  TerrainConfig flat;
  flat.flat_only = true;
  flat.mean_depth_m = 10.0;
  const Terrain terrain = Terrain::generate(flat, {{-100, -100}, {100, 100}});
  const SonarConfig sonar;  // 512 beams over 140 degrees, default noise
  const double vehicle_depth = 1.0;
  const Eigen::Isometry3d pose = vehicle_pose({0, 0, 0, vehicle_depth, 0, 0, 90.0}, {});
  auto rng = make_rng(1, kSonarNoiseStream);
  const std::vector<Beam> beams = ping(terrain, pose, sonar, rng);
  ASSERT_EQ(beams.size(), 512u);
  float port = 0, starboard = 0;
  for (const Beam& b : beams) {
    port = std::min(port, b.across);
    starboard = std::max(starboard, b.across);
  }
  const double altitude = flat.mean_depth_m - vehicle_depth;
  const double expected = 2.0 * altitude * std::tan(70.0 * M_PI / 180.0);
  EXPECT_NEAR(starboard - port, expected, 0.02 * expected);
  // Nadir beams see the bottom at the altitude, within the range noise.
  const Beam& nadir = beams[256];
  EXPECT_NEAR(nadir.down, altitude, 4 * (0.05 + 0.002 * altitude));
}

TEST(Sonar, BeamsLandOnTheTerrainWithConfiguredNoise) {
  TerrainConfig config;
  config.seed = 5;
  const Terrain terrain = Terrain::generate(config, {{0, 0}, {200, 200}});
  SonarConfig sonar;
  const Eigen::Isometry3d pose = vehicle_pose({0, 100, 100, 1.0, 2.0, -1.0, 30.0}, {});
  auto rng = make_rng(2, kSonarNoiseStream);
  const std::vector<Beam> beams = ping(terrain, pose, sonar, rng);
  ASSERT_GT(beams.size(), 500u);
  double sum_sq = 0;
  for (const Beam& b : beams) {
    const Eigen::Vector3d p = pose * Eigen::Vector3d(b.along, b.across, b.down);
    sum_sq += std::pow(p.z() - terrain.elevation(p.x(), p.y()), 2);
  }
  // Vertical miss is the range noise projected on the vertical: at most ~0.07 m rms here.
  EXPECT_LT(std::sqrt(sum_sq / beams.size()), 0.08);
  EXPECT_GT(std::sqrt(sum_sq / beams.size()), 0.01);
}

}  // namespace
}  // namespace bathyslam::sim
