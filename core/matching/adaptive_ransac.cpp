#include "core/matching/adaptive_ransac.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "core/types/median.h"

namespace bathyslam {
namespace {

// Least-squares rigid transform (Kabsch/Umeyama without scale) taking `from` onto `to`.
Eigen::Isometry3d rigid_fit(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target,
                            const std::vector<int>& use) {
  Eigen::Matrix3Xd from(3, use.size()), to(3, use.size());
  for (std::size_t k = 0; k < use.size(); ++k) {
    from.col(static_cast<Eigen::Index>(k)) = source[use[k]];
    to.col(static_cast<Eigen::Index>(k)) = target[use[k]];
  }
  Eigen::Isometry3d t;
  t.matrix() = Eigen::umeyama(from, to, false);
  return t;
}

// Three points nearly on a line leave the rotation about that line free.
bool degenerate(const std::vector<Eigen::Vector3d>& points, const std::vector<int>& sample) {
  const Eigen::Vector3d a = points[sample[1]] - points[sample[0]], b = points[sample[2]] - points[sample[0]];
  return a.cross(b).norm() < 0.5;  // twice the triangle's area, m^2
}

// Largest distance between where `a` and `b` put any of the points.
double largest_displacement(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const std::vector<Eigen::Vector3d>& points) {
  double largest = 0;
  for (const Eigen::Vector3d& p : points) largest = std::max(largest, (a * p - b * p).norm());
  return largest;
}

void find_competitor(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target,
                     const RansacConfig& config, RansacResult& winner);

}  // namespace

RansacResult adaptive_ransac(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target,
                             const RansacConfig& config) {
  RansacResult best;
  const int n = static_cast<int>(source.size());
  if (n < config.sample_size) return best;
  std::mt19937_64 rng(config.seed);
  double threshold = config.initial_threshold_m;
  const auto target_inliers = static_cast<std::size_t>(std::ceil(config.target_inlier_ratio * n));
  std::vector<int> sample, inliers;
  std::vector<double> errors(n);

  for (int iteration = 0; iteration < config.max_iterations && best.inliers.size() < target_inliers; ++iteration) {
    best.iterations = iteration + 1;
    // PROSAC: draw from the best-ranked matches first and widen the pool as iterations pass.
    const int pool = std::min(n, std::max(config.sample_size, iteration / 10 + config.sample_size));
    sample.clear();
    while (static_cast<int>(sample.size()) < config.sample_size) {
      const int k = std::uniform_int_distribution<int>(0, pool - 1)(rng);
      if (std::find(sample.begin(), sample.end(), k) == sample.end()) sample.push_back(k);
    }
    if (config.sample_size == 3 && (degenerate(source, sample) || degenerate(target, sample))) continue;
    const Eigen::Isometry3d candidate = rigid_fit(source, target, sample);

    inliers.clear();
    for (int i = 0; i < n; ++i) {
      errors[i] = (candidate * source[i] - target[i]).norm();
      if (errors[i] < threshold) inliers.push_back(i);
    }
    if (inliers.size() <= best.inliers.size()) continue;
    best.source_to_target = candidate;
    best.inliers = inliers;
    if (static_cast<int>(inliers.size()) >= config.min_inliers) {
      // MAD of the inlier errors: the threshold follows the noise the data actually has.
      std::vector<double> inlier_errors;
      for (int i : inliers) inlier_errors.push_back(errors[i]);
      const double med = median(inlier_errors);
      for (double& e : inlier_errors) e = std::abs(e - med);
      const double mad = median(inlier_errors);
      threshold = std::clamp(med + config.mad_scale * 1.4826 * mad, config.min_threshold_m, config.initial_threshold_m);
    }
  }

  if (static_cast<int>(best.inliers.size()) >= config.min_inliers) {
    best.source_to_target = rigid_fit(source, target, best.inliers);
    best.inliers.clear();
    for (int i = 0; i < n; ++i) {
      if ((best.source_to_target * source[i] - target[i]).norm() < threshold) best.inliers.push_back(i);
    }
  }
  best.threshold_m = threshold;
  best.inlier_ratio = static_cast<double>(best.inliers.size()) / n;
  if (config.find_competitor && static_cast<int>(best.inliers.size()) >= config.min_inliers) {
    find_competitor(source, target, config, best);
  }
  return best;
}

namespace {

// RANSAC on the matches the winner left out, at the winner's threshold: a transform that
// explains many of them and lies far from the winner is a second solution of the pair.
void find_competitor(const std::vector<Eigen::Vector3d>& source, const std::vector<Eigen::Vector3d>& target,
                     const RansacConfig& config, RansacResult& winner) {
  std::vector<Eigen::Vector3d> rest_source, rest_target;
  std::vector<bool> inlier(source.size(), false);
  for (int i : winner.inliers) inlier[i] = true;
  for (std::size_t i = 0; i < source.size(); ++i) {
    if (inlier[i]) continue;
    rest_source.push_back(source[i]);
    rest_target.push_back(target[i]);
  }
  // The competitor is judged at the winner's tolerance, not a looser one of its own.
  RansacConfig rest = config;
  rest.find_competitor = false;
  rest.initial_threshold_m = rest.min_threshold_m = winner.threshold_m;
  rest.seed = config.seed + 1;
  const RansacResult competitor = adaptive_ransac(rest_source, rest_target, rest);
  if (static_cast<int>(competitor.inliers.size()) < config.min_inliers) return;
  const double separation = largest_displacement(winner.source_to_target, competitor.source_to_target, source);
  if (separation < config.competitor_separation_m) return;  // the same solution, noisier matches
  winner.competitor_inliers = static_cast<int>(competitor.inliers.size());
  winner.competitor_separation_m = separation;
}

}  // namespace
}  // namespace bathyslam
