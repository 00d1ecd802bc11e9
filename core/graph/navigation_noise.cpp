#include "core/graph/navigation_noise.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "core/graph/loop_consistency.h"

namespace bathyslam {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

double huber(double m2, double threshold) {
  return m2 <= threshold ? m2 : 2.0 * std::sqrt(threshold * m2) - threshold;
}

// One innovation with its covariance split by source: S = s_t²·A + s_ψ²·B + R, R the
// registration's own and that of the heading steps modelled so far.
struct Term {
  Eigen::Vector3d d;
  Eigen::Matrix3d a, b, r;
  int first_step = 0, end_step = 0;  // the odometry steps it spans: [first_step, end_step)
  double turn_sign = 1;              // +1 when it runs forward along the chain
  Eigen::Vector3d to_position;       // DR's, map axes
  Eigen::Matrix3d from_level;        // DR's heading at `from`: level frame to map axes
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

// The translation scale that fits best at yaw scale 10^log_yaw, and its cost: one axis of
// minimise's grid.
struct ProfilePoint {
  double log_t = 0, cost = 0;
};

ProfilePoint profile_over_translation(const std::vector<Term>& terms, const std::vector<char>& kept, double log_yaw,
                                      double lowest) {
  ProfilePoint best{lowest, kInfinity};
  auto search = [&](double centre, double half, double delta) {
    for (double lt = std::max(lowest, centre - half); lt <= std::min(0.0, centre + half) + 1e-9; lt += delta) {
      const double c = cost(terms, kept, lt, log_yaw, kInfinity);
      if (c < best.cost) best = {lt, c};
    }
  };
  search(lowest / 2, -lowest / 2, 0.2);
  search(best.log_t, 0.2, 0.05);
  search(best.log_t, 0.05, 0.01);
  return best;
}

// The loosest heading the innovations do not rule out (the profile likelihood within `rise` of
// its least, bisection to 0.01 decades above the likeliest) and the translation that fits best
// with it: a point on the likelihood's ridge, never both scales loosened at once.
Scales loosest_heading(const std::vector<Term>& terms, const std::vector<char>& kept, Scales likeliest, double rise,
                       double lowest) {
  const double least = cost(terms, kept, likeliest.log_t, likeliest.log_yaw, kInfinity);
  Scales loosest = likeliest;  // the loosest heading found allowed, and its translation
  double outside = 0.0;        // the tightest heading found ruled out
  // Whether `log_yaw` is allowed; if so it becomes `loosest`.
  auto try_heading = [&](double log_yaw) {
    const ProfilePoint p = profile_over_translation(terms, kept, log_yaw, lowest);
    if (p.cost - least > rise) return false;
    loosest = {p.log_t, log_yaw};
    return true;
  };
  if (try_heading(outside)) return loosest;
  while (outside - loosest.log_yaw > 0.01) {
    const double middle = 0.5 * (loosest.log_yaw + outside);
    if (!try_heading(middle)) outside = middle;
  }
  return loosest;
}

// The scales that maximise the likelihood (Huber's loss first, then the Gaussian likelihood of the
// innovations explained, trimmed again under each new fit until the set holds), and which
// innovations they explain.
struct Fit {
  Scales scales;
  std::vector<char> explained;
  int count = 0;
};

std::vector<char> explained_under(const std::vector<Term>& terms, Scales scales, double chi2) {
  std::vector<char> explained(terms.size());
  for (std::size_t k = 0; k < terms.size(); ++k) {
    const Eigen::Matrix3d s = covariance(terms[k], scales.log_t, scales.log_yaw);
    explained[k] = terms[k].d.dot(s.ldlt().solve(terms[k].d)) <= chi2;
  }
  return explained;
}

Fit fit(const std::vector<Term>& terms, const NavigationNoiseConfig& config, double lowest) {
  std::vector<char> kept(terms.size(), 1);
  Scales scales = minimise(terms, kept, config.outlier_chi2, lowest);
  for (int pass = 0; pass < 5; ++pass) {
    const std::vector<char> explained = explained_under(terms, scales, config.outlier_chi2);
    if (pass > 0 && explained == kept) break;
    if (std::count(explained.begin(), explained.end(), 1) < config.min_registrations) break;
    kept = explained;
    scales = minimise(terms, kept, std::numeric_limits<double>::infinity(), lowest);
  }
  Fit f{scales, explained_under(terms, scales, config.outlier_chi2), 0};
  f.count = static_cast<int>(std::count(f.explained.begin(), f.explained.end(), 1));
  return f;
}

struct Jump {
  int step = -1;    // the odometry step from node `step` to the next
  double turn = 0;  // −(DR's heading jump there), as the innovations see it
};

// The odometry step whose heading jump best explains the innovations across it: a jump ε at step
// m (about node m + 1) changes a registration's innovation by −ε·g, g = ±(ẑ × (p_to − p_{m+1}) in
// `from`'s level frame, 1), + running forward along the chain. Over the innovations spanning m,
// the least-squares ε under each one's covariance S (Σ gᵀS⁻¹d / Σ gᵀS⁻¹g) and its share of their
// weighted sum of squares ((Σ gᵀS⁻¹d)² / Σ gᵀS⁻¹g): the registrations that agree with dead
// reckoning pull it towards no jump wherever they span, and the lever arms place it. Only steps
// that an innovation `fit` leaves unexplained spans are tried.
Jump best_jump(const std::vector<Term>& terms, const Fit& fit, const std::vector<Eigen::Isometry3d>& dead_reckoning) {
  const int steps = static_cast<int>(dead_reckoning.size()) - 1;
  std::vector<char> tried(std::max(steps, 0), 0);
  for (std::size_t k = 0; k < terms.size(); ++k) {
    if (fit.explained[k]) continue;
    for (int m = terms[k].first_step; m < terms[k].end_step && m < steps; ++m) tried[m] = 1;
  }
  std::vector<Eigen::Matrix3d> information(terms.size());
  for (std::size_t k = 0; k < terms.size(); ++k) {
    information[k] = covariance(terms[k], fit.scales.log_t, fit.scales.log_yaw).inverse();
  }
  Jump best;
  double best_gain = 0;
  for (int m = 0; m < steps; ++m) {
    if (!tried[m]) continue;
    const Eigen::Vector3d pivot = dead_reckoning[m + 1].translation();
    double sum_a = 0, sum_b = 0;
    for (std::size_t k = 0; k < terms.size(); ++k) {
      const Term& t = terms[k];
      if (m < t.first_step || m >= t.end_step) continue;
      const Eigen::Vector3d lever = t.to_position - pivot;
      const Eigen::Vector3d sideways = t.from_level.transpose() * Eigen::Vector3d(-lever.y(), lever.x(), 0.0);
      const Eigen::Vector3d g = t.turn_sign * Eigen::Vector3d(sideways.x(), sideways.y(), 1.0);
      const Eigen::Vector3d ig = information[k] * g;
      sum_a += ig.dot(t.d);
      sum_b += ig.dot(g);
    }
    if (sum_b <= 0) continue;
    const double gain = sum_a * sum_a / sum_b;
    if (gain > best_gain) best_gain = gain, best = {m, sum_a / sum_b};
  }
  return best;
}

// The variance a heading step of `sigma` at odometry step `step` adds to each innovation: its
// first-order effect (DrNoiseModel's) and the turn's second-order radial one, l·σ²/2 at a lever
// arm l, which at degrees over hundreds of metres is metres.
void add_heading_step(std::vector<Term>& terms, const std::vector<DrInnovation>& innovations,
                      const std::vector<Eigen::Isometry3d>& dead_reckoning, const GraphConfig& prior, int step, double sigma) {
  GraphConfig one_step = prior;
  one_step.dr_sigma_translation_m.setZero();
  one_step.dr_sigma_rotation_rad.setZero();
  one_step.step_yaw_sigma_rad = {{step, sigma}};
  const DrNoiseModel stepped(dead_reckoning, one_step);
  const Eigen::Vector3d pivot = dead_reckoning[step + 1].translation();
  for (std::size_t k = 0; k < terms.size(); ++k) {
    Term& t = terms[k];
    t.r += xy_yaw_block(stepped.covariance(innovations[k].from, innovations[k].to));
    if (step < t.first_step || step >= t.end_step) continue;
    const Eigen::Vector3d lever = t.from_level.transpose() * (t.to_position - pivot);
    const Eigen::Vector2d radial = lever.head<2>() * (sigma * sigma / 2);
    t.r.topLeftCorner<2, 2>() += radial * radial.transpose();
  }
}

}  // namespace

DrInnovation dr_innovation(const PoseGraphEdge& edge, const DrNoiseModel& dr,
                           const std::vector<Eigen::Isometry3d>& dead_reckoning) {
  const LoopCandidate measured = loop_candidate(edge, dead_reckoning);
  return {edge.from, edge.to, pose_difference(measured.measured, dr.relative_pose(edge.from, edge.to)), measured.covariance};
}

GraphConfig alias_graph(const NavigationNoiseEstimate& estimate, const NavigationNoiseConfig& config) {
  const bool at_bound = estimate.likeliest_yaw_scale <= config.min_scale * (1 + 1e-6);
  return at_bound ? estimate.graph : estimate.likeliest_graph;
}

NavigationNoiseEstimate estimate_navigation_noise(const std::vector<Eigen::Isometry3d>& dead_reckoning,
                                                  const std::vector<DrInnovation>& innovations, const GraphConfig& prior,
                                                  const NavigationNoiseConfig& config,
                                                  const std::vector<NavigationNoiseEstimate::HeadingStep>& known_steps) {
  NavigationNoiseEstimate out;
  out.graph = prior;
  out.likeliest_graph = prior;
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
    t.first_step = std::min(i.from, i.to);
    t.end_step = std::max(i.from, i.to);
    t.turn_sign = i.from < i.to ? 1.0 : -1.0;
    t.to_position = dead_reckoning[i.to].translation();
    t.from_level = level_frame(dead_reckoning[i.from]).linear();
    terms.push_back(t);
  }

  // Heading steps found before stay: their variance is in the innovations the white noise is fitted to.
  for (const NavigationNoiseEstimate::HeadingStep& h : known_steps) {
    if (h.step < 0 || h.step + 1 >= static_cast<int>(dead_reckoning.size())) continue;
    add_heading_step(terms, innovations, dead_reckoning, prior, h.step, std::abs(h.jump_rad));
    out.graph.step_yaw_sigma_rad[h.step] = std::abs(h.jump_rad);
    out.heading_steps.push_back(h);
  }

  // Huber's loss over all innovations first: convex in the residuals, so wrong registrations can
  // only widen the noise, never explain it away. Then the Gaussian likelihood of those the noise
  // found could be explained (χ²₃ 99.9 %), trimmed again under each new estimate until the set
  // holds: a few wrong registrations would otherwise still widen it several times over.
  const double lowest = std::log10(config.min_scale);
  Fit best = fit(terms, config, lowest);

  // Heading steps, one at a time while each explains enough of what the noise leaves out.
  for (auto found = out.heading_steps.size(); found < static_cast<std::size_t>(config.max_heading_steps) && dead_reckoning.size() > 1;
       ++found) {
    const Jump jump = best_jump(terms, best, dead_reckoning);
    if (jump.step < 0) break;
    std::vector<Term> with_step = terms;
    add_heading_step(with_step, innovations, dead_reckoning, prior, jump.step, std::abs(jump.turn));
    const Fit next = fit(with_step, config, lowest);
    const int explained = next.count - best.count;  // of the same innovations
    if (explained < config.min_registrations) break;
    out.graph.step_yaw_sigma_rad[jump.step] = std::abs(jump.turn);
    out.heading_steps.push_back({jump.step, -jump.turn, explained});
    terms = std::move(with_step);
    best = next;
  }
  out.estimated = true;
  out.likeliest_translation_scale = std::pow(10.0, best.scales.log_t);
  out.likeliest_yaw_scale = std::pow(10.0, best.scales.log_yaw);
  const Scales published = config.confidence_chi2 > 0
                               ? loosest_heading(terms, best.explained, best.scales, config.confidence_chi2, lowest)
                               : best.scales;
  out.translation_scale = std::pow(10.0, published.log_t);
  out.yaw_scale = std::pow(10.0, published.log_yaw);
  out.likeliest_graph = out.graph;
  out.likeliest_graph.dr_sigma_translation_m.head<2>() *= out.likeliest_translation_scale;
  out.likeliest_graph.dr_sigma_rotation_rad.z() *= out.likeliest_yaw_scale;
  out.graph.dr_sigma_translation_m.head<2>() *= out.translation_scale;
  out.graph.dr_sigma_rotation_rad.z() *= out.yaw_scale;
  return out;
}

}  // namespace bathyslam
