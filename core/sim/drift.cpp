#include "core/sim/drift.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "core/sim/random.h"
#include "core/sim/trajectory.h"

namespace bathyslam::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Position, depth and heading: the four degrees of freedom dead reckoning drifts in.
struct Pose4 {
  double east = 0, north = 0, depth = 0, yaw = 0;  // yaw: heading in radians, clockwise

  static Pose4 of(const NavSample& s) { return {s.easting, s.northing, s.depth_m, s.heading_deg * kDeg}; }
  Eigen::Vector2d forward() const { return {std::sin(yaw), std::cos(yaw)}; }
  Eigen::Vector2d right() const { return {std::cos(yaw), -std::sin(yaw)}; }
};

// `b` seen from `a`: forward, right, down and yaw offsets.
Pose4 between(const Pose4& a, const Pose4& b) {
  const Eigen::Vector2d d(b.east - a.east, b.north - a.north);
  return {d.dot(a.forward()), d.dot(a.right()), b.depth - a.depth, b.yaw - a.yaw};
}

Pose4 compose(const Pose4& a, const Pose4& rel) {
  const Eigen::Vector2d p = Eigen::Vector2d(a.east, a.north) + rel.east * a.forward() +
                            rel.north * a.right();
  return {p.x(), p.y(), a.depth + rel.depth, a.yaw + rel.yaw};
}

NavSample with_pose(NavSample s, const Pose4& p) {
  s.easting = p.east;
  s.northing = p.north;
  s.depth_m = p.depth;
  s.heading_deg = std::fmod(std::fmod(p.yaw / kDeg, 360.0) + 360.0, 360.0);
  return s;
}

double mean_paper_error(const std::vector<NavSample>& truth, double sigma_yaw) {
  PaperDrift drift;
  drift.sigma_yaw_rad = sigma_yaw;
  double sum = 0;
  constexpr int kSeeds = 64;
  for (int seed = 0; seed < kSeeds; ++seed) {
    sum += drift_stats(apply_paper_drift(truth, truth.front().time, drift, 1000 + seed), truth).mean_m;
  }
  return sum / kSeeds;
}

}  // namespace

double calibrated_paper_sigma_yaw() {
  static const double sigma = [] {
    const MotionConfig motion;
    const auto stride = static_cast<std::size_t>(std::lround(0.5 / motion.step_s));  // 2 Hz is plenty
    const auto truth = navigation_of(drive(survey_pattern(Scenario::kLake), motion), stride);
    // The error is nearly linear in sigma_yaw; two secant steps settle it.
    double s = 5e-4;
    for (int i = 0; i < 2; ++i) s *= kPaperMeanDrError_m / mean_paper_error(truth, s);
    return s;
  }();
  return sigma;
}

std::vector<NavSample> apply_paper_drift(const std::vector<NavSample>& truth, double key_time,
                                         const PaperDrift& drift, uint64_t seed) {
  const double sigma_yaw = drift.sigma_yaw_rad > 0 ? drift.sigma_yaw_rad : calibrated_paper_sigma_yaw();
  auto rng = make_rng(seed, kDriftStream);
  std::normal_distribution<double> translation(0.0, drift.sigma_translation_m);
  std::normal_distribution<double> yaw(0.0, sigma_yaw);

  std::vector<NavSample> dr;
  dr.reserve(truth.size());
  bool keyed = false;
  Pose4 true_key, dr_key;
  double next_key = key_time;
  for (const NavSample& s : truth) {
    const Pose4 pose = Pose4::of(s);
    if (s.time >= next_key) {
      if (!keyed) {
        dr_key = pose;  // the first submap's pose is shared
        keyed = true;
      } else {
        Pose4 rel = between(true_key, pose);
        rel.east += translation(rng);
        rel.north += translation(rng);
        rel.depth += translation(rng);
        rel.yaw += yaw(rng);
        dr_key = compose(dr_key, rel);
      }
      true_key = pose;
      while (next_key <= s.time) next_key += drift.submap_duration_s;
    }
    dr.push_back(keyed ? with_pose(s, compose(dr_key, between(true_key, pose))) : s);
  }
  return dr;
}

DvlDrift make_heading_walk_drift() {
  DvlDrift drift;
  drift.heading_bias_walk_rad_per_sqrt_s = 2.5e-3;  // RMSE ~27 m on lake averaged over seeds (docs/simulator.md)
  return drift;
}

HeadingStep draw_compass_step(const std::vector<NavSample>& truth, const CompassStepDrift& drift,
                              uint64_t seed) {
  if (truth.empty()) throw std::invalid_argument("draw_compass_step: no navigation");
  // A stream of its own: the dvl drift underneath stays the seed's.
  auto rng = make_rng(seed, kCompassStepStream);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double span = truth.back().time - truth.front().time;
  const double fraction = drift.earliest + (drift.latest - drift.earliest) * unit(rng);
  const double magnitude_deg = drift.min_step_deg + (drift.max_step_deg - drift.min_step_deg) * unit(rng);
  const double sign = unit(rng) < 0.5 ? -1.0 : 1.0;
  return {truth.front().time + fraction * span, sign * magnitude_deg * kDeg};
}

std::vector<NavSample> apply_dvl_drift(const std::vector<NavSample>& truth, const DvlDrift& drift,
                                       uint64_t seed, std::optional<HeadingStep> step) {
  auto rng = make_rng(seed, kDriftStream);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double scale = 1.0 + drift.scale_sigma * normal(rng);
  double bias = drift.heading_bias_sigma_rad * normal(rng);

  std::vector<NavSample> dr;
  dr.reserve(truth.size());
  Pose4 estimate = Pose4::of(truth.front());
  dr.push_back(truth.front());
  for (std::size_t i = 1; i < truth.size(); ++i) {
    const Pose4 a = Pose4::of(truth[i - 1]), b = Pose4::of(truth[i]);
    const double dt = truth[i].time - truth[i - 1].time;
    // The DVL measures the displacement in the vehicle frame; the INS heading carries the bias.
    const Pose4 rel = between(a, b);
    const double forward = scale * rel.east + drift.velocity_noise_m_s * dt * normal(rng);
    const double right = scale * rel.north + drift.velocity_noise_m_s * dt * normal(rng);
    estimate.yaw = a.yaw + bias;
    estimate = compose(estimate, {forward, right, 0.0, 0.0});
    bias += drift.heading_bias_walk_rad_per_sqrt_s * std::sqrt(dt) * normal(rng);
    if (step && truth[i].time >= step->time) {
      bias += step->step_rad;  // the reading from here on, and so the track after it
      step.reset();
    }
    estimate.depth = b.depth;  // from the pressure sensor
    estimate.yaw = b.yaw + bias;
    dr.push_back(with_pose(truth[i], estimate));
  }
  return dr;
}

DriftStats drift_stats(const std::vector<NavSample>& nav, const std::vector<NavSample>& reference) {
  if (nav.size() != reference.size() || nav.empty()) {
    throw std::invalid_argument("drift_stats: navigation and reference differ in length");
  }
  DriftStats stats;
  double sum = 0, sum_sq = 0;
  for (std::size_t i = 0; i < nav.size(); ++i) {
    const double e = std::hypot(nav[i].easting - reference[i].easting,
                                nav[i].northing - reference[i].northing);
    sum += e;
    sum_sq += e * e;
    stats.max_m = std::max(stats.max_m, e);
    if (i > 0) {
      stats.distance_travelled_m += std::hypot(reference[i].easting - reference[i - 1].easting,
                                               reference[i].northing - reference[i - 1].northing);
    }
  }
  stats.mean_m = sum / nav.size();
  stats.rms_m = std::sqrt(sum_sq / nav.size());
  stats.end_m = std::hypot(nav.back().easting - reference.back().easting,
                           nav.back().northing - reference.back().northing);
  return stats;
}

}  // namespace bathyslam::sim
