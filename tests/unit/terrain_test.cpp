#include "core/sim/terrain.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

namespace bathyslam::sim {
namespace {

// Standard deviation of the terrain about its best-fit plane in a square window: the local
// roughness, free of the gentle regional slope.
double detrended_std(const Terrain& t, double cx, double cy, double half_m) {
  std::vector<Eigen::Vector3d> pts;
  for (double x = cx - half_m; x <= cx + half_m; x += 0.5) {
    for (double y = cy - half_m; y <= cy + half_m; y += 0.5) pts.emplace_back(x, y, t.elevation(x, y));
  }
  Eigen::MatrixXd a(pts.size(), 3);
  Eigen::VectorXd z(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    a.row(i) << pts[i].x() - cx, pts[i].y() - cy, 1.0;
    z(i) = pts[i].z();
  }
  const Eigen::VectorXd coef = a.colPivHouseholderQr().solve(z);
  const Eigen::VectorXd r = z - a * coef;
  return std::sqrt(r.squaredNorm() / r.size());
}

TEST(Terrain, HasFlatAndRoughRegionsDifferingTenfoldInStd) {
  TerrainConfig config;
  config.seed = 7;
  const Terrain t = Terrain::generate(config, {{0, 0}, {740, 300}});
  std::vector<double> flat, rough;
  for (double x = 10; x < 740; x += 10) {
    for (double y = 10; y < 300; y += 10) {
      const double w = t.roughness_weight(x, y);
      if (w < 0.01) flat.push_back(detrended_std(t, x, y, 5.0));
      if (w > 0.99) rough.push_back(detrended_std(t, x, y, 5.0));
    }
  }
  ASSERT_GT(flat.size(), 100u) << "the lake area must have flat lakebed";
  ASSERT_GT(rough.size(), 100u) << "the lake area must have undulating regions";
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  const double flat_std = median(flat), rough_std = median(rough);
  EXPECT_GT(rough_std, 10.0 * flat_std) << "flat " << flat_std << " m, rough " << rough_std << " m";
}

TEST(Terrain, MeanDepthIsKept) {
  TerrainConfig config;
  const Terrain t = Terrain::generate(config, {{0, 0}, {300, 200}});
  double sum = 0;
  int n = 0;
  for (double x = 0; x < 300; x += 2) {
    for (double y = 0; y < 200; y += 2, ++n) sum += t.elevation(x, y);
  }
  EXPECT_NEAR(sum / n, -config.mean_depth_m, 1.5);
}

TEST(Terrain, SameSeedSameSurfaceDifferentSeedDifferent) {
  TerrainConfig a, b, c;
  a.seed = b.seed = 3;
  c.seed = 4;
  const Area area{{0, 0}, {100, 100}};
  const Terrain ta = Terrain::generate(a, area), tb = Terrain::generate(b, area),
                tc = Terrain::generate(c, area);
  double same = 0, different = 0;
  for (double x = 0; x < 100; x += 1.3) {
    for (double y = 0; y < 100; y += 1.7) {
      same = std::max(same, std::abs(ta.elevation(x, y) - tb.elevation(x, y)));
      different = std::max(different, std::abs(ta.elevation(x, y) - tc.elevation(x, y)));
    }
  }
  EXPECT_EQ(same, 0.0);
  EXPECT_GT(different, 0.1);
}

}  // namespace
}  // namespace bathyslam::sim
