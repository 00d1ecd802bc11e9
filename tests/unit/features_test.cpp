#include "core/features/tsd_keypoints.h"

#include <gtest/gtest.h>

#include <random>

#include "core/features/terrain_grid.h"
#include "tests/unit/synthetic_terrain.h"

namespace bathyslam {
namespace {

TEST(TerrainGrid, InterpolatesAPlaneAndMasksCellsWithoutSoundings) {
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 100; ++i) {
    for (int j = 0; j < 50; ++j) {
      const double x = 0.2 * i, y = 0.2 * j;
      if (i > 40 && i < 60) continue;  // no soundings for 8 < x < 12, wider than the IDW radius
      points.emplace_back(x, y, static_cast<float>(10 + 0.1 * x));  // z down
    }
  }
  const TerrainGrid grid = grid_terrain(points, {});
  int checked = 0;
  for (int r = 0; r < grid.rows(); ++r) {
    for (int c = 0; c < grid.cols(); ++c) {
      const Eigen::Vector2d xy = grid.position(c, r);
      const bool in_gap = xy.x() > 8.6 && xy.x() < 11.4;
      EXPECT_EQ(grid.valid.at<uint8_t>(r, c) == 0, in_gap) << "cell at " << xy.transpose();
      // IDW is one-sided at the edges of the data, so only interior cells are exact.
      if (!grid.valid.at<uint8_t>(r, c) || xy.x() < 1 || xy.x() > 19 || (xy.x() > 7.5 && xy.x() < 12.5)) continue;
      EXPECT_NEAR(grid.elevation.at<float>(r, c), -(10 + 0.1 * xy.x()), 0.02);
      ++checked;
    }
  }
  EXPECT_GT(checked, 300);
}

TEST(TsdKeypoints, LandOnPlantedMoundsAndNotOnANoisyFlatPlane) {
  const SyntheticTerrain terrain = SyntheticTerrain::with_mounds(7);
  const TerrainGrid rough = grid_terrain(terrain.sample(Eigen::Isometry3d::Identity(), 0.03, 1), {});
  const std::vector<Keypoint> keypoints = detect_keypoints(rough);
  ASSERT_GT(keypoints.size(), 20u);
  for (const Keypoint& k : keypoints) {
    EXPECT_GT(terrain.elevation(k.position.head<2>()) + 10.0, 0.02)
        << "keypoint at " << k.position.transpose() << " is on the flat bottom, off every mound";
  }

  const SyntheticTerrain flat = SyntheticTerrain::flat();
  const TerrainGrid plane = grid_terrain(flat.sample(Eigen::Isometry3d::Identity(), 0.05, 2), {});
  EXPECT_EQ(detect_keypoints(plane).size(), 0u) << "noise alone makes no keypoints";
}

// The same ground gridded in a frame turned by 37 degrees: the descriptor of a keypoint matches
// the descriptor of the keypoint at the same place.
TEST(TsdKeypoints, DescriptorMatchesItsOwnPatchRotatedBy37Degrees) {
  const SyntheticTerrain terrain = SyntheticTerrain::with_mounds(11);
  const std::vector<Keypoint> a = detect_keypoints(grid_terrain(terrain.sample(Eigen::Isometry3d::Identity(), 0.0, 3), {}));
  Eigen::Isometry3d turned = Eigen::Isometry3d::Identity();
  turned.linear() = Eigen::AngleAxisd(37.0 * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  turned.translation() = Eigen::Vector3d(4.3, -2.1, 0);
  // Soundings in frame b are turned.inverse() * world.
  const std::vector<Keypoint> b = detect_keypoints(grid_terrain(terrain.sample(turned, 0.0, 4), {}));
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());

  int compared = 0, correlated = 0;
  for (const Keypoint& ka : a) {
    const Eigen::Vector3d in_b = turned.inverse() * ka.position;
    for (const Keypoint& kb : b) {
      if ((kb.position - in_b).head<2>().norm() > 0.3) continue;
      ++compared;
      correlated += descriptor_ncc(ka.descriptor, kb.descriptor) >= 0.95 ? 1 : 0;
      break;
    }
  }
  ASSERT_GT(compared, 10);
  EXPECT_GE(correlated, 0.9 * compared) << correlated << " of " << compared << " correlate at 0.95 or more";
}

// The match score is the mean squared difference; given a bound below it, the score stops at
// or above the bound (so a matcher comparing against its second best decides the same), and a
// bound above it changes nothing.
TEST(TsdKeypoints, DescriptorMseStopsOnlyPastItsBound) {
  std::mt19937_64 rng(7);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  Eigen::VectorXf a(121), b(121);
  for (int i = 0; i < 121; ++i) a[i] = noise(rng), b[i] = noise(rng);
  double exact = 0;
  for (int i = 0; i < 121; ++i) exact += double(a[i] - b[i]) * double(a[i] - b[i]);
  exact /= 121;
  EXPECT_NEAR(descriptor_mse(a, b), exact, 1e-12);
  EXPECT_NEAR(descriptor_mse(a, b, 2 * exact), exact, 1e-12);
  EXPECT_GE(descriptor_mse(a, b, 0.5 * exact), 0.5 * exact);
  EXPECT_LT(descriptor_mse(a, b, 0.05 * exact), exact) << "stopped early";
}

}  // namespace
}  // namespace bathyslam
