#include "core/sim/sonar.h"

#include <cmath>
#include <optional>

namespace bathyslam::sim {
namespace {

// Distance along the ray to the terrain. Steps are bounded by the height above the terrain and
// the terrain's steepest slope, so the march cannot jump through a ridge (sphere tracing); a
// minimum step keeps grazing rays from stalling, and bisection finds the crossing it brackets.
std::optional<double> range_to_bottom(const Terrain& terrain, const Eigen::Vector3d& origin,
                                      const Eigen::Vector3d& direction, double max_range_m) {
  constexpr double kMinStepM = 0.05;
  const double bound = -direction.z() + terrain.max_slope() * direction.head<2>().norm();
  if (direction.z() >= 0 || bound <= 0) return std::nullopt;  // pointing up: never reaches
  auto height = [&](double s) {
    const Eigen::Vector3d p = origin + s * direction;
    return p.z() - terrain.elevation(p.x(), p.y());
  };
  double above = 0, h = height(0);
  if (h <= 0) return std::nullopt;  // the sonar is in the bottom
  while (above < max_range_m) {
    const double next = above + std::max(h / bound, kMinStepM);
    const double h_next = height(next);
    if (h_next <= 0) {
      double below = next;
      for (int i = 0; i < 30 && below - above > 1e-5; ++i) {
        const double mid = 0.5 * (above + below);
        (height(mid) > 0 ? above : below) = mid;
      }
      return 0.5 * (above + below);
    }
    above = next;
    h = h_next;
  }
  return std::nullopt;
}

// Millimetres: finer than any sonar resolves, and prints short in the bundle.
float to_mm(double metres) { return static_cast<float>(std::round(metres * 1000.0) / 1000.0); }

}  // namespace

double beam_angle_rad(const SonarConfig& config, int index) {
  const double half = 0.5 * config.swath_deg * M_PI / 180.0;
  return -half + 2.0 * half * index / (config.beams - 1);
}

std::vector<Beam> ping(const Terrain& terrain, const Eigen::Isometry3d& true_pose,
                       const SonarConfig& config, std::mt19937_64& rng) {
  std::normal_distribution<double> unit(0.0, 1.0);
  std::vector<Beam> beams;
  beams.reserve(config.beams);
  for (int i = 0; i < config.beams; ++i) {
    const double angle = beam_angle_rad(config, i);
    const Eigen::Vector3d in_vehicle(0.0, std::sin(angle), std::cos(angle));  // fwd, stbd, down
    const Eigen::Vector3d in_map = true_pose.linear() * in_vehicle;
    const auto range = range_to_bottom(terrain, true_pose.translation(), in_map, config.max_range_m);
    const double draw = unit(rng);  // drawn for every beam, so a miss does not shift the rest
    if (!range) continue;
    const double depth_below_sonar = -*range * in_map.z();
    const double sigma = config.noise_base_m + config.noise_depth_fraction * depth_below_sonar;
    const Eigen::Vector3d sounding = (*range + sigma * draw) * in_vehicle;
    beams.push_back({static_cast<uint32_t>(i), to_mm(sounding.x()), to_mm(sounding.y()),
                     to_mm(sounding.z())});
  }
  return beams;
}

}  // namespace bathyslam::sim
