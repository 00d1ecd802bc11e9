#pragma once
// A small analytic seafloor for feature tests: Gaussian mounds (asymmetric, so each has a
// dominant direction) on a flat bottom 10 m below the vehicle, sampled as soundings in any
// submap frame.
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

namespace bathyslam {

// A pose at (x, y) turned `yaw_deg` about z: how the tests place submap frames on the terrain.
inline Eigen::Isometry3d planar_pose(double x, double y, double yaw_deg) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = Eigen::Vector3d(x, y, 0);
  p.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return p;
}

struct SyntheticTerrain {
  std::vector<Eigen::Vector2d> mounds;  // world (x, y)
  std::vector<double> heights, stretch, angle;
  double mound_sigma_m = 2.0;
  double extent_m = 40.0;  // the square [0, extent]^2 in world coordinates

  static SyntheticTerrain flat() { return {}; }

  static SyntheticTerrain with_mounds(uint64_t seed, int count = 12) {
    SyntheticTerrain t;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> where(6.0, t.extent_m - 6.0), height(0.8, 1.6), s(1.3, 2.0),
        turn(0, M_PI);
    while (static_cast<int>(t.mounds.size()) < count) {
      const Eigen::Vector2d p(where(rng), where(rng));
      bool apart = true;
      for (const auto& q : t.mounds) apart = apart && (p - q).norm() > 7.0;
      if (!apart) continue;
      t.mounds.push_back(p);
      t.heights.push_back(height(rng));
      t.stretch.push_back(s(rng));
      t.angle.push_back(turn(rng));
    }
    return t;
  }

  // Elevation (up) at a world position.
  double elevation(const Eigen::Vector2d& p) const {
    double h = -10.0;
    for (std::size_t k = 0; k < mounds.size(); ++k) {
      const Eigen::Vector2d d = Eigen::Rotation2Dd(-angle[k]) * (p - mounds[k]);
      const double u = d.x() / (stretch[k] * mound_sigma_m), v = d.y() / mound_sigma_m;
      h += heights[k] * std::exp(-0.5 * (u * u + v * v));
    }
    return h;
  }

  // Soundings every 0.2 m over the square, with vertical noise, in the submap frame whose pose
  // in the world is `frame` (z down in that frame, as submaps store them).
  std::vector<Eigen::Vector3f> sample(const Eigen::Isometry3d& frame, double noise_m, uint64_t seed) const {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0.0, noise_m > 0 ? noise_m : 1e-12);
    std::vector<Eigen::Vector3f> points;
    for (double x = 0; x <= extent_m; x += 0.2) {
      for (double y = 0; y <= extent_m; y += 0.2) {
        const Eigen::Vector3d world(x, y, -(elevation({x, y}) + noise(rng)));  // z down
        points.push_back((frame.inverse() * world).cast<float>());
      }
    }
    return points;
  }
};

}  // namespace bathyslam
