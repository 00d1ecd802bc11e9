// The uniqueness probe: a periodic seabed fits itself one wavelength along, mounds do not.
#include "core/register/uniqueness.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/unit/synthetic_terrain.h"

namespace bathyslam {
namespace {

// Soundings every 0.25 m over a 40 x 40 m square of `elevation` (up, world frame), in the
// submap frame at `frame` (z down), with 2 cm noise.
template <typename Elevation>
TerrainGrid grid_of(const Elevation& elevation, const Eigen::Isometry3d& frame, double x0, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<Eigen::Vector3f> points;
  for (double x = x0; x <= x0 + 40; x += 0.25) {
    for (double y = 0; y <= 40; y += 0.25) {
      const Eigen::Vector3d world(x, y, -(elevation(Eigen::Vector2d(x, y)) + noise(rng)));
      points.push_back((frame.inverse() * world).cast<float>());
    }
  }
  return grid_terrain(points);
}

// Two submaps that overlap by 30 m in x, the second turned and shifted; probed at the truth.
template <typename Elevation>
Uniqueness probe_at_truth(const Elevation& elevation) {
  const Eigen::Isometry3d target_frame = planar_pose(0, 0, 0), source_frame = planar_pose(10, 2, 7);
  const TerrainGrid target = grid_of(elevation, target_frame, 0, 1), source = grid_of(elevation, source_frame, 10, 2);
  return probe_uniqueness(target, source, target_frame.inverse() * source_frame);
}

TEST(Uniqueness, SandWavesFitOneWavelengthAlongAcrossTheirCrests) {
  const double wavelength = 9.0;
  const Eigen::Vector2d across = Eigen::Vector2d(std::cos(0.5), std::sin(0.5));
  const Eigen::Vector2d along(-across.y(), across.x());
  // Crests that rise and fall along their length, as real ones do: only a shift across them by
  // whole wavelengths fits again.
  auto sand_waves = [&](const Eigen::Vector2d& p) {
    const double height = 0.5 + 0.3 * std::sin(2 * M_PI * along.dot(p) / 23.0);
    return -10.0 + height * std::sin(2 * M_PI * across.dot(p) / wavelength);
  };
  const Uniqueness u = probe_at_truth(sand_waves);
  ASSERT_TRUE(u.probed);
  EXPECT_LT(u.distinctness(), 3.0);
  EXPECT_NEAR(u.alternative_offset_m.norm(), wavelength, 1.0);
  EXPECT_GT(std::abs(u.alternative_offset_m.normalized().dot(across)), 0.9) << "the alias lies across the crests";
}

TEST(Uniqueness, MoundsFitOnlyWhereTheyAre) {
  const SyntheticTerrain mounds = SyntheticTerrain::with_mounds(5);
  const Uniqueness u = probe_at_truth([&](const Eigen::Vector2d& p) { return mounds.elevation(p); });
  ASSERT_TRUE(u.probed);
  EXPECT_LT(u.cost_at_answer_m2, 0.01);
  EXPECT_GT(u.distinctness(), 25.0);
}

// Steps of whole cells reuse one set of bilinear samples, shifted; any other step samples at
// each offset. Both must see the same seabed: a step a micrometre off whole cells takes the
// second way to (nearly) the same offsets.
TEST(Uniqueness, WholeCellStepsCostWhatSamplingEachOffsetCosts) {
  const SyntheticTerrain mounds = SyntheticTerrain::with_mounds(5);
  auto elevation = [&](const Eigen::Vector2d& p) { return mounds.elevation(p); };
  const Eigen::Isometry3d target_frame = planar_pose(0, 0, 0), source_frame = planar_pose(10, 2, 7);
  const TerrainGrid target = grid_of(elevation, target_frame, 0, 1), source = grid_of(elevation, source_frame, 10, 2);
  const Eigen::Isometry3d answer = planar_pose(0.3, -0.2, 1) * target_frame.inverse() * source_frame;
  // Radii between lattice points, so that both probes compare the same set of offsets.
  UniquenessConfig whole;
  whole.search_radius_m = 23.5;
  whole.local_radius_m = 5.5;
  whole.exclusion_m = 3.2;
  UniquenessConfig sampled = whole;
  sampled.step_m = whole.step_m + 1e-6;
  const Uniqueness a = probe_uniqueness(target, source, answer, whole);
  const Uniqueness b = probe_uniqueness(target, source, answer, sampled);
  ASSERT_TRUE(a.probed && b.probed);
  EXPECT_NEAR(a.cost_at_answer_m2, b.cost_at_answer_m2, 1e-9);
  EXPECT_NEAR(a.typical_cost_m2, b.typical_cost_m2, 1e-3 * a.typical_cost_m2);
  EXPECT_NEAR(a.local_cost_m2, b.local_cost_m2, 1e-3 * a.local_cost_m2);
  EXPECT_NEAR(a.alternative_cost_m2, b.alternative_cost_m2, 1e-3 * a.alternative_cost_m2);
  EXPECT_LT((a.alternative_offset_m - b.alternative_offset_m).norm(), 1e-3);
}

TEST(Uniqueness, AFlatBottomHasNoUniqueAnswer) {
  const Uniqueness u = probe_at_truth([](const Eigen::Vector2d&) { return -10.0; });
  ASSERT_TRUE(u.probed);
  EXPECT_LT(u.distinctness(), 3.0);
  // Everything compared competes, so the competing region runs on past it on every side.
  const std::vector<Eigen::Vector2d> open = u.competitor_offsets(true);
  ASSERT_FALSE(open.empty());
  Eigen::Vector2d lowest = open.front(), highest = open.front();
  for (const Eigen::Vector2d& o : open) lowest = lowest.cwiseMin(o), highest = highest.cwiseMax(o);
  EXPECT_LT(lowest.x(), -10.0);
  EXPECT_GT(highest.x(), 10.0);
  EXPECT_LT(lowest.y(), -10.0);
  EXPECT_GT(highest.y(), 10.0);
  for (const Eigen::Vector2d& o : open) EXPECT_GT(o.norm(), 5.0) << "only at the rim of what was compared";
}

// Mounds: nothing competes, so nothing runs on.
TEST(Uniqueness, MoundsLeaveNoOpenCompetitors) {
  const SyntheticTerrain mounds = SyntheticTerrain::with_mounds(5);
  const Uniqueness u = probe_at_truth([&](const Eigen::Vector2d& p) { return mounds.elevation(p); });
  EXPECT_TRUE(u.competitor_offsets(true).empty());
}

}  // namespace
}  // namespace bathyslam
