#include "core/graph/navigation_noise.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "core/graph/loop_consistency.h"

namespace bathyslam {
namespace {

double huber(double m2, double threshold) {
  return m2 <= threshold ? m2 : 2.0 * std::sqrt(threshold * m2) - threshold;
}

// One innovation with its covariance split by source: S = s_t²·A + s_ψ²·B + R.
struct Term {
  Eigen::Vector3d d;
  Eigen::Matrix3d a, b, r;
};

Eigen::Matrix3d covariance(const Term& t, double log_t, double log_yaw) {
  return std::pow(10.0, 2 * log_t) * t.a + std::pow(10.0, 2 * log_yaw) * t.b + t.r;
}

// −2 log-likelihood (up to a constant) at scales 10^log_t, 10^log_yaw of the terms `kept`, each
// m² through Huber's loss at `huber_chi2` (infinite: Gaussian).
double cost(const std::vector<Term>& terms, const std::vector<char>& kept, double log_t, double log_yaw,
            double huber_chi2) {
  double sum = 0;
  for (std::size_t k = 0; k < terms.size(); ++k) {
    if (!kept[k]) continue;
    const Eigen::LLT<Eigen::Matrix3d> llt(covariance(terms[k], log_t, log_yaw));
    if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
    const Eigen::Matrix3d l = llt.matrixL();
    sum += 2.0 * l.diagonal().array().log().sum() + huber(terms[k].d.dot(llt.solve(terms[k].d)), huber_chi2);
  }
  return sum;
}

struct Scales {
  double log_t = 0, log_yaw = 0;
};

// The cost's minimum over [lowest, 0]² in log10 scales: a grid 0.2 decades apart over all of it,
// then 0.05 and 0.01 apart about the best so far.
Scales minimise(const std::vector<Term>& terms, const std::vector<char>& kept, double huber_chi2, double lowest) {
  Scales best{lowest, lowest};
  double best_cost = std::numeric_limits<double>::infinity();
  auto search = [&](Scales centre, double half, double delta) {
    for (double lt = std::max(lowest, centre.log_t - half); lt <= std::min(0.0, centre.log_t + half) + 1e-9; lt += delta) {
      for (double ly = std::max(lowest, centre.log_yaw - half); ly <= std::min(0.0, centre.log_yaw + half) + 1e-9;
           ly += delta) {
        const double c = cost(terms, kept, lt, ly, huber_chi2);
        if (c < best_cost) best_cost = c, best = {lt, ly};
      }
    }
  };
  search({lowest / 2, lowest / 2}, -lowest / 2, 0.2);
  search(best, 0.2, 0.05);
  search(best, 0.05, 0.01);
  return best;
}

}  // namespace

DrInnovation dr_innovation(const PoseGraphEdge& edge, const DrNoiseModel& dr,
                           const std::vector<Eigen::Isometry3d>& dead_reckoning) {
  const LoopCandidate measured = loop_candidate(edge, dead_reckoning);
  return {edge.from, edge.to, pose_difference(measured.measured, dr.relative_pose(edge.from, edge.to)), measured.covariance};
}

NavigationNoiseEstimate estimate_navigation_noise(const std::vector<Eigen::Isometry3d>& dead_reckoning,
                                                  const std::vector<DrInnovation>& innovations, const GraphConfig& prior,
                                                  const NavigationNoiseConfig& config) {
  NavigationNoiseEstimate out;
  out.graph = prior;
  out.innovations = static_cast<int>(innovations.size());
  if (!config.estimate || out.innovations < config.min_registrations) return out;

  // DR's covariance is linear in each step's variances: one model per scaled source.
  GraphConfig horizontal = prior, heading = prior;
  horizontal.dr_sigma_translation_m.z() = 0;
  horizontal.dr_sigma_rotation_rad.setZero();
  heading.dr_sigma_translation_m.setZero();
  heading.dr_sigma_rotation_rad.head<2>().setZero();
  const DrNoiseModel per_translation(dead_reckoning, horizontal), per_yaw(dead_reckoning, heading);
  std::vector<Term> terms;
  terms.reserve(innovations.size());
  for (const DrInnovation& i : innovations) {
    Term t;
    t.d = Eigen::Vector3d(i.difference(0), i.difference(1), i.difference(5));  // what the DR gate tests
    t.a = xy_yaw_block(per_translation.covariance(i.from, i.to));
    t.b = xy_yaw_block(per_yaw.covariance(i.from, i.to));
    t.r = xy_yaw_block(i.measurement);
    terms.push_back(t);
  }

  // Huber's loss over all innovations first: convex in the residuals, so wrong registrations can
  // only widen the noise, never explain it away. Then the Gaussian likelihood of those the noise
  // found could be explained (χ²₃ 99.9 %), trimmed again under each new estimate until the set
  // holds: a few wrong registrations would otherwise still widen it several times over.
  const double lowest = std::log10(config.min_scale);
  std::vector<char> kept(terms.size(), 1);
  Scales scales = minimise(terms, kept, config.outlier_chi2, lowest);
  for (int pass = 0; pass < 5; ++pass) {
    std::vector<char> explained(terms.size());
    for (std::size_t k = 0; k < terms.size(); ++k) {
      const Eigen::Matrix3d s = covariance(terms[k], scales.log_t, scales.log_yaw);
      explained[k] = terms[k].d.dot(s.ldlt().solve(terms[k].d)) <= config.outlier_chi2;
    }
    if (pass > 0 && explained == kept) break;
    if (std::count(explained.begin(), explained.end(), 1) < config.min_registrations) break;
    kept = explained;
    scales = minimise(terms, kept, std::numeric_limits<double>::infinity(), lowest);
  }
  const double best_t = scales.log_t, best_yaw = scales.log_yaw;

  out.estimated = true;
  out.translation_scale = std::pow(10.0, best_t);
  out.yaw_scale = std::pow(10.0, best_yaw);
  out.graph.dr_sigma_translation_m.head<2>() *= out.translation_scale;
  out.graph.dr_sigma_rotation_rad.z() *= out.yaw_scale;
  return out;
}

}  // namespace bathyslam
