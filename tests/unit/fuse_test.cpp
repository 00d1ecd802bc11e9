#include "core/fuse/fuse.h"
#include "core/fuse/map_resolution.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace bathyslam {
namespace {

constexpr LocalOrigin kOrigin{452000.0, 4630000.0};

Eigen::Isometry3d pose(double x, double y, double z, double yaw) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = Eigen::Vector3d(x, y, z);
  p.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return p;
}

// Soundings of the surface `elevation(x, y)` (map frame) over [x0, x0 + size) × [y0, y0 + size),
// with Gaussian noise, expressed in the frame of `submap_pose` as a submap stores them.
template <typename Surface>
Submap sample(const Surface& elevation, double x0, double y0, double size, int n, double sigma,
              const Eigen::Isometry3d& submap_pose, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, size);
  std::normal_distribution<double> noise(0, sigma);
  Submap s;
  s.dr_pose = submap_pose;
  const Eigen::Isometry3d to_submap = submap_pose.inverse();
  for (int k = 0; k < n; ++k) {
    const double x = x0 + u(rng), y = y0 + u(rng);
    s.points.push_back((to_submap * Eigen::Vector3d(x, y, elevation(x, y) + noise(rng))).cast<float>());
  }
  return s;
}

SubmapSet set_of(std::vector<Submap> submaps) {
  SubmapSet set;
  set.origin = kOrigin;
  for (std::size_t i = 0; i < submaps.size(); ++i) submaps[i].index = static_cast<int>(i);
  set.submaps = std::move(submaps);
  return set;
}

std::vector<Eigen::Isometry3d> dr_poses(const SubmapSet& set) {
  std::vector<Eigen::Isometry3d> poses;
  for (const Submap& s : set.submaps) poses.push_back(s.dr_pose);
  return poses;
}

TEST(Fuse, PlacesASoundingInTheCrsCellOfItsPosedPosition) {
  // A submap posed 3.3 m east, 7.9 m north and turned 90°: its point (1, 0, -12) lands at map
  // (3.3, 8.9), i.e. CRS (452003.3, 4630008.9), global cell (904006, 9260017) at 0.5 m.
  SubmapSet set = set_of({Submap{}});
  set.submaps[0].points = {Eigen::Vector3f(1, 0, -12)};
  const std::vector<Eigen::Isometry3d> poses = {pose(3.3, 7.9, 0, M_PI / 2)};
  const GridRaster map = fuse_submaps(set, poses, {0.5, 1});
  ASSERT_EQ(map.geometry.width, 1);
  ASSERT_EQ(map.geometry.height, 1);
  EXPECT_EQ(map.geometry.left, 904006);
  EXPECT_EQ(map.geometry.top, 9260017);
  EXPECT_NEAR(map.elevation[0], -12.0f, 1e-5);
  EXPECT_EQ(map.count[0], 1.0f);
  EXPECT_TRUE(std::isnan(map.uncertainty[0])) << "one sounding says nothing about spread";
}

TEST(Fuse, FlatPlaneGivesItsElevationWithinThreeSigmaOverRootNAndTheNoiseAsUncertainty) {
  constexpr double kDepth = -10.0, kSigma = 0.05;
  std::mt19937 rng(11);
  auto plane = [](double, double) { return kDepth; };
  // Four overlapping submaps with different poses over a 20 m square: ~40 soundings per cell.
  std::vector<Submap> submaps;
  for (int k = 0; k < 4; ++k) {
    submaps.push_back(sample(plane, 0, 0, 20, 16000, kSigma, pose(5.0 * k, 3.0 - k, -kDepth, 0.4 * k), rng));
  }
  const SubmapSet set = set_of(submaps);
  const GridRaster map = fuse_submaps(set, dr_poses(set), {0.5, 3});
  ASSERT_EQ(map.geometry.width, 40);
  ASSERT_EQ(map.geometry.height, 40);

  double total = 0, weighted = 0;
  int within = 0, cells = 0;
  std::vector<float> uncertainty;
  for (std::size_t i = 0; i < map.geometry.cells(); ++i) {
    ASSERT_TRUE(map.valid(i));
    const double n = map.count[i];
    ++cells;
    within += std::fabs(map.elevation[i] - kDepth) <= 3 * kSigma / std::sqrt(n);
    total += n;
    weighted += n * map.elevation[i];
    uncertainty.push_back(map.uncertainty[i]);
  }
  EXPECT_EQ(total, 64000);
  EXPECT_NEAR(weighted / total, kDepth, 3 * kSigma / std::sqrt(total));
  EXPECT_GE(within, 0.99 * cells) << "cells whose mean misses the plane by more than 3σ/√n";
  std::nth_element(uncertainty.begin(), uncertainty.begin() + cells / 2, uncertainty.end());
  EXPECT_NEAR(uncertainty[cells / 2], kSigma, 0.1 * kSigma) << "median per-cell standard deviation";
}

TEST(Fuse, CellsWithFewerThanTheMinimumSoundingsAreNoData) {
  SubmapSet set = set_of({Submap{}});
  // Two soundings in cell (0, 0) of the local origin, three in the cell east of it.
  set.submaps[0].points = {{0.1f, 0.1f, -5}, {0.2f, 0.2f, -5}, {0.6f, 0.1f, -6}, {0.7f, 0.2f, -6}, {0.8f, 0.3f, -7}};
  const GridRaster map = fuse_submaps(set, dr_poses(set), {0.5, 3});
  ASSERT_EQ(map.geometry.width, 1) << "the extent covers only cells with data";
  EXPECT_EQ(map.geometry.left, 904001);
  EXPECT_FLOAT_EQ(map.elevation[0], -19.0f / 3);
  EXPECT_FLOAT_EQ(map.uncertainty[0], std::sqrt(1.0f / 3));

  const GridRaster lenient = fuse_submaps(set, dr_poses(set), {0.5, 2});
  ASSERT_EQ(lenient.geometry.width, 2);
  EXPECT_FLOAT_EQ(lenient.elevation[0], -5.0f);
  EXPECT_FLOAT_EQ(lenient.count[0], 2.0f);
}

TEST(Fuse, ScatteredPosesAreRefusedBeforeTheRasterIsMade) {
  // Two submaps, the second placed 300 km east and north: 3.6e11 cells at 0.5 m, never allocated.
  SubmapSet set = set_of({Submap{}, Submap{}});
  for (Submap& submap : set.submaps) submap.points = {{0.1f, 0.1f, -5}, {0.2f, 0.2f, -5}, {0.3f, 0.1f, -6}};
  std::vector<Eigen::Isometry3d> poses = dr_poses(set);
  poses[1].translation() += Eigen::Vector3d(300e3, 300e3, 0);
  try {
    fuse_submaps(set, poses, {.resolution_m = 0.5, .min_soundings = 3, .max_cells = 100'000'000});
    FAIL() << "a map of 300 km was made";
  } catch (const std::length_error& error) {
    EXPECT_NE(std::string(error.what()).find("map: the soundings cover 300000 m × 300000 m: 360001200001 cells"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("over the limit of 100000000"), std::string::npos) << error.what();
  }
  EXPECT_EQ(fuse_submaps(set, dr_poses(set), {.resolution_m = 0.5, .min_soundings = 3, .max_cells = 1}).valid_cells(), 1u);
}

// A survey sailing east at 1 m per ping, 101 beams across `swath` metres each ping.
Survey straight_survey(int pings, double swath) {
  Survey survey;
  for (int i = 0; i <= pings; ++i) survey.nav.push_back({.time = double(i), .easting = double(i), .heading_deg = 90});
  for (int i = 0; i < pings; ++i) {
    survey.pings.push_back({double(i) + 0.5, static_cast<uint32_t>(survey.beams.size()), 101});
    for (int b = 0; b <= 100; ++b)
      survey.beams.push_back({static_cast<uint32_t>(b), 0, static_cast<float>(swath * (b / 100.0 - 0.5)), 10});
  }
  return survey;
}

TEST(MapResolution, TheCellFollowsTheSoundingDensity) {
  // 101 soundings per 100 m² swept: a 4 m cell holds 16, the first of 0.5 · 2^k to hold 2 × 3.
  const SweptArea sparse = swept_area(straight_survey(200, 100));
  EXPECT_NEAR(sparse.track_m, 199, 1e-9);
  EXPECT_NEAR(sparse.swath_m, 100, 1e-4);
  EXPECT_NEAR(sparse.density_per_m2(), 200 * 101 / (199.0 * 100), 1e-9);
  EXPECT_EQ(auto_map_resolution(straight_survey(200, 100), 3), 4.0);
  EXPECT_EQ(auto_map_resolution(straight_survey(200, 10), 3), 1.0);  // 10 per m²: 0.5 m cells would hold 2.5
  // A vehicle near the seabed (50 per m²; the simulator's 46): never finer than 0.5 m.
  EXPECT_EQ(auto_map_resolution(straight_survey(200, 2), 3), 0.5);
  EXPECT_EQ(auto_map_resolution(Survey{}, 3), 0.5);
}

TEST(MapResolution, AStrayFixOrAGapNeitherLengthensTheTrackNorCoarsensTheCells) {
  // Coarser cells would let the extent check pass a survey with a fix 500 km away.
  Survey stray = straight_survey(200, 100);
  stray.nav[120].easting += 500e3;
  EXPECT_NEAR(swept_area(stray).track_m, 199, 1e-9);
  EXPECT_EQ(auto_map_resolution(stray, 3), 4.0);
  // A second file an hour later and 330 km away: the pause is not sailed.
  Survey apart = straight_survey(200, 100);
  const Survey later = straight_survey(200, 100);
  for (NavSample nav : later.nav) {
    nav.time += 3600;
    nav.easting += 330e3;
    apart.nav.push_back(nav);
  }
  for (Ping ping : later.pings) {
    ping.time += 3600;
    ping.first_beam += static_cast<uint32_t>(apart.beams.size());
    apart.pings.push_back(ping);
  }
  apart.beams.insert(apart.beams.end(), later.beams.begin(), later.beams.end());
  EXPECT_NEAR(swept_area(apart).track_m, 398, 1e-9);
  EXPECT_EQ(auto_map_resolution(apart, 3), 4.0);
}

TEST(Fuse, MemoryFollowsTheAreaNotTheSoundings) {
  std::mt19937 rng(3);
  const Submap s = sample([](double, double) { return -10.0; }, 0, 0, 30, 100000, 0.05, Eigen::Isometry3d::Identity(), rng);
  GridFuser fuser(kOrigin);
  fuser.add(s.points, s.dr_pose);
  const std::size_t cells_once = fuser.allocated_cells();
  for (int k = 0; k < 9; ++k) fuser.add(s.points, s.dr_pose);
  EXPECT_EQ(fuser.allocated_cells(), cells_once);
  EXPECT_EQ(fuser.soundings(), 1000000u);
  EXPECT_EQ(fuser.raster().valid_cells(), 3600u);
}

TEST(Fuse, SeamBetweenMisplacedSubmapsVanishesWithCorrectedPoses) {
  // Undulating ground, two submaps over the same 20 m square; the second's dead reckoning is off
  // by 2 m east and 0.5 m up, so its copy of the terrain sits beside the first's.
  constexpr double kSigma = 0.03;
  auto terrain = [](double x, double y) { return -10.0 + 0.8 * std::sin(x / 4.0) + 0.5 * std::cos(y / 3.0); };
  std::mt19937 rng(7);
  const Eigen::Isometry3d truth_a = pose(10, 10, 10, 0), truth_b = pose(12, 9, 10, 0.3);
  const Eigen::Isometry3d error = pose(2.0, 0, 0.5, 0);
  const SubmapSet set = set_of({sample(terrain, 0, 0, 20, 30000, kSigma, truth_a, rng),
                                sample(terrain, 0, 0, 20, 30000, kSigma, truth_b, rng)});
  const std::vector<Eigen::Isometry3d> drifted = {truth_a, error * truth_b}, corrected = {truth_a, truth_b};

  auto median_uncertainty = [&](const std::vector<Eigen::Isometry3d>& poses) {
    const GridRaster map = fuse_submaps(set, poses, {0.5, 10});
    std::vector<float> u;
    for (std::size_t i = 0; i < map.geometry.cells(); ++i) {
      if (map.valid(i)) u.push_back(map.uncertainty[i]);
    }
    std::nth_element(u.begin(), u.begin() + u.size() / 2, u.end());
    return u[u.size() / 2];
  };
  const float seam = median_uncertainty(drifted), healed = median_uncertainty(corrected);
  EXPECT_GT(seam, 0.15f) << "two copies of the terrain 2 m and 0.5 m apart";
  // What is left with the right poses is the noise plus the terrain's slope within a cell.
  EXPECT_LT(healed, 2 * kSigma);
  EXPECT_LT(healed, seam / 5);
}

TEST(Fuse, RejectsAPoseCountThatDoesNotMatchTheSubmaps) {
  const SubmapSet set = set_of({Submap{}, Submap{}});
  const std::vector<Eigen::Isometry3d> one = {Eigen::Isometry3d::Identity()};
  EXPECT_THROW(fuse_submaps(set, one), std::invalid_argument);
}

}  // namespace
}  // namespace bathyslam
