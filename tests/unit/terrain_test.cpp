#include "core/sim/terrain.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <numeric>

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

// Residuals of a profile about its best-fit line: the regional slope taken out.
std::vector<double> detrended(const std::vector<double>& z) {
  const double n = static_cast<double>(z.size());
  double st = 0, sz = 0, stt = 0, stz = 0;
  for (std::size_t i = 0; i < z.size(); ++i) {
    st += i;
    sz += z[i];
    stt += static_cast<double>(i) * i;
    stz += i * z[i];
  }
  const double slope = (n * stz - st * sz) / (n * stt - st * st);
  const double offset = (sz - slope * st) / n;
  std::vector<double> r(z.size());
  for (std::size_t i = 0; i < z.size(); ++i) r[i] = z[i] - offset - slope * i;
  return r;
}

double rms(const std::vector<double>& v) {
  return std::sqrt(std::inner_product(v.begin(), v.end(), v.begin(), 0.0) / v.size());
}

// Elevations every `step_m` along a line from `from` in direction `d` (unit).
std::vector<double> profile(const Terrain& t, const Eigen::Vector2d& from, const Eigen::Vector2d& d,
                            double length_m, double step_m) {
  std::vector<double> z;
  for (double s = 0; s <= length_m; s += step_m) {
    const Eigen::Vector2d p = from + s * d;
    z.push_back(t.elevation(p.x(), p.y()));
  }
  return z;
}

// Detrended standard deviation of every 10 m window of the area.
std::vector<double> window_stds(const Terrain& t, const Area& area) {
  std::vector<double> stds;
  for (double x = area.min.x() + 5; x + 5 <= area.max.x(); x += 10) {
    for (double y = area.min.y() + 5; y + 5 <= area.max.y(); y += 10) stds.push_back(detrended_std(t, x, y, 5.0));
  }
  return stds;
}

TerrainConfig of_kind(TerrainKind kind, uint64_t seed) {
  TerrainConfig config;
  config.kind = kind;
  config.seed = seed;
  return config;
}

Eigen::Vector2d towards(double angle_deg) {
  return {std::cos(angle_deg * M_PI / 180.0), std::sin(angle_deg * M_PI / 180.0)};
}

TEST(SandWaves, PeriodAcrossTheCrestsIsTheWavelengthAndAlongThemLittleChanges) {
  TerrainConfig config = of_kind(TerrainKind::kSandWaves, 5);
  config.sand_wavelength_fixed_m = 17.0;
  config.sand_crest_angle_fixed_deg = 35.0;
  const Terrain t = Terrain::generate(config, {{0, 0}, {200, 200}});
  const Eigen::Vector2d along = towards(35.0), across = towards(125.0);
  constexpr double kStep = 0.25;
  const std::vector<double> z = detrended(profile(t, {130, 30}, across, 150.0, kStep));
  // Autocorrelation: the best lag between 5 and 30 m is one wavelength.
  auto correlation = [&](std::size_t lag) {
    double sum = 0;
    for (std::size_t i = 0; i + lag < z.size(); ++i) sum += z[i] * z[i + lag];
    return sum / (z.size() - lag);
  };
  std::size_t best = 0;
  for (auto lag = static_cast<std::size_t>(5 / kStep); lag <= 30 / kStep; ++lag) {
    if (best == 0 || correlation(lag) > correlation(best)) best = lag;
  }
  EXPECT_NEAR(best * kStep, 17.0, 1.0);
  EXPECT_GT(correlation(best), 0.5 * correlation(0)) << "the period dominates";

  // Along a crest (the highest point of a wavelength near the middle), 40 m either way.
  const auto middle = z.size() / 2;
  const auto crest = std::max_element(z.begin() + middle, z.begin() + middle + 17 / kStep) - z.begin();
  const Eigen::Vector2d on_crest = Eigen::Vector2d(130, 30) + crest * kStep * across;
  const std::vector<double> along_crest = detrended(profile(t, on_crest - 20 * along, along, 40.0, kStep));
  EXPECT_LT(rms(along_crest), 0.3 * rms(z)) << "along " << rms(along_crest) << " m, across " << rms(z) << " m";
}

TEST(SandWaves, CrestsAreObliqueToTheLinesAndTheSeedPicksTheWavelength) {
  for (uint64_t seed : {1, 2, 3}) {
    const Terrain t = Terrain::generate(of_kind(TerrainKind::kSandWaves, seed), {{0, 0}, {120, 120}});
    // East-west and north-south profiles both cross crests when they are oblique.
    const std::vector<double> east = detrended(profile(t, {0, 60}, {1, 0}, 120, 0.5));
    const std::vector<double> north = detrended(profile(t, {60, 0}, {0, 1}, 120, 0.5));
    EXPECT_GT(rms(east), 0.05) << "seed " << seed;
    EXPECT_GT(rms(north), 0.05) << "seed " << seed;
  }
}

TEST(Flat, DetrendedStdBelowThreeCentimetresInEveryTenMetreWindow) {
  const Area area{{0, 0}, {150, 150}};
  const Terrain t = Terrain::generate(of_kind(TerrainKind::kFlat, 4), area);
  const std::vector<double> stds = window_stds(t, area);
  EXPECT_LT(*std::max_element(stds.begin(), stds.end()), 0.03);
}

TEST(Boulders, MostlyFlatWithIsolatedBumpsHigherThanFortyCentimetres) {
  const Area area{{0, 0}, {200, 200}};
  const Terrain t = Terrain::generate(of_kind(TerrainKind::kBoulders, 6), area);
  const std::vector<double> stds = window_stds(t, area);
  const auto flat = std::count_if(stds.begin(), stds.end(), [](double s) { return s < 0.03; });
  EXPECT_GT(flat, static_cast<long>(0.7 * stds.size())) << "most of the area is flat sand";

  // Points over 0.4 m above their window's plane, gathered into bumps 3 m apart.
  std::vector<Eigen::Vector2d> high;
  for (double cx = 5; cx < 200; cx += 10) {
    for (double cy = 5; cy < 200; cy += 10) {
      const double base = t.elevation(cx - 5, cy - 5) + t.elevation(cx + 5, cy + 5);
      for (double x = cx - 5; x < cx + 5; x += 0.25) {
        for (double y = cy - 5; y < cy + 5; y += 0.25) {
          if (t.elevation(x, y) - 0.5 * base > 0.4) high.emplace_back(x, y);
        }
      }
    }
  }
  std::vector<std::vector<Eigen::Vector2d>> bumps;
  for (const Eigen::Vector2d& p : high) {
    auto near = std::find_if(bumps.begin(), bumps.end(), [&](const auto& b) { return (b.front() - p).norm() < 3.0; });
    if (near == bumps.end()) bumps.push_back({p}); else near->push_back(p);
  }
  EXPECT_GE(bumps.size(), 10u);
  for (const auto& b : bumps) {
    double across = 0;
    for (const auto& p : b) across = std::max(across, (p - b.front()).norm());
    EXPECT_LT(across, 3.0) << "a bump no wider than a boulder";
  }
}

TEST(Channel, ADepressionDeeperThanThreeMetresAndRoughnessOnlyInsideIt) {
  const Area area{{0, 0}, {200, 200}};
  const Terrain t = Terrain::generate(of_kind(TerrainKind::kChannel, 3), area);
  std::vector<double> z;
  for (double x = 0; x <= 200; x += 1) {
    for (double y = 0; y <= 200; y += 1) z.push_back(t.elevation(x, y));
  }
  std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
  const double plain = z[z.size() / 2];
  EXPECT_GT(plain - *std::min_element(z.begin(), z.end()), 3.0);
  int plain_windows = 0;
  for (double x = 5; x < 200; x += 10) {
    for (double y = 5; y < 200; y += 10) {
      double inside = 0;
      for (double u = x - 5; u <= x + 5; u += 0.5) {
        for (double v = y - 5; v <= y + 5; v += 0.5) inside = std::max(inside, t.roughness_weight(u, v));
      }
      if (inside == 0.0) {
        EXPECT_LT(detrended_std(t, x, y, 5.0), 0.03) << "outside the banks at " << x << ", " << y;
        ++plain_windows;
      }
    }
  }
  EXPECT_GT(plain_windows, 100) << "the channel leaves most of the area a plain";
}

TEST(SlopeBreak, SlopeAtLeastThreeTimesSteeperBelowTheBreakThanOnTheShelf) {
  TerrainConfig config = of_kind(TerrainKind::kSlopeBreak, 2);
  config.break_angle_fixed_deg = 30.0;
  const Terrain t = Terrain::generate(config, {{0, 0}, {300, 300}});
  // The break runs through the centre; downslope is to the right of its direction.
  const Eigen::Vector2d centre(150, 150), line = towards(30.0), downslope(line.y(), -line.x());
  auto gradient = [&](double from_s, double to_s) {
    double sum = 0;
    for (double l = -40; l <= 40; l += 10) {
      const Eigen::Vector2d a = centre + l * line + from_s * downslope;
      const Eigen::Vector2d b = centre + l * line + to_s * downslope;
      sum += (t.elevation(a.x(), a.y()) - t.elevation(b.x(), b.y())) / (to_s - from_s);
    }
    return sum / 9;
  };
  const double shelf = gradient(-60, -15), slope = gradient(6, 16);
  EXPECT_GT(shelf, 0.005) << "the shelf deepens towards the break";
  EXPECT_GT(slope, 3.0 * shelf) << "shelf " << shelf << ", slope " << slope;
}

TEST(Mixed, HasFlatAndRoughPatches) {
  const Area area{{0, 0}, {300, 300}};
  const Terrain t = Terrain::generate(of_kind(TerrainKind::kMixed, 8), area);
  const std::vector<double> stds = window_stds(t, area);
  EXPECT_GT(std::count_if(stds.begin(), stds.end(), [](double s) { return s < 0.03; }), 20);
  EXPECT_GT(std::count_if(stds.begin(), stds.end(), [](double s) { return s > 0.1; }), 20);
}

TEST(Terrain, EveryKindKeepsTheMeanDepthAndItsSeed) {
  for (TerrainKind kind : {TerrainKind::kSandWaves, TerrainKind::kBoulders, TerrainKind::kChannel,
                           TerrainKind::kSlopeBreak, TerrainKind::kFlat, TerrainKind::kMixed}) {
    const Area area{{0, 0}, {200, 150}};
    const Terrain a = Terrain::generate(of_kind(kind, 9), area), b = Terrain::generate(of_kind(kind, 9), area);
    double sum = 0, same = 0;
    int n = 0;
    for (double x = 0; x <= 200; x += 2) {
      for (double y = 0; y <= 150; y += 2, ++n) {
        sum += a.elevation(x, y);
        same = std::max(same, std::abs(a.elevation(x, y) - b.elevation(x, y)));
      }
    }
    EXPECT_NEAR(sum / n, -10.0, 0.3) << to_string(kind);
    EXPECT_EQ(same, 0.0) << to_string(kind);
    EXPECT_EQ(parse_terrain_kind(to_string(kind)), kind);
  }
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
