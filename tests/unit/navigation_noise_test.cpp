// The survey's own dead-reckoning noise, estimated from its registrations: it recovers the noise
// a simulated navigation was drifted with, keeps Table 1 when the registrations are too few,
// is not inflated by a wrong registration, and the DR gate under it refuses what Table 1 lets by.
#include "core/graph/navigation_noise.h"

#include <gtest/gtest.h>

#include <random>

#include "core/graph/loop_consistency.h"

namespace bathyslam {
namespace {

Eigen::Isometry3d pose(double x, double y, double yaw) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = Eigen::Vector3d(x, y, -10.0);
  p.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return p;
}

// A lawnmower of `lines` lines of `n` submaps 20 m apart, lines 30 m apart, and its dead
// reckoning: every step's heading off by white noise of `sigma_yaw` rad.
struct Lawnmower {
  std::vector<Eigen::Isometry3d> truth, dr;
  int n = 0;
  int node(int line, int along) const { return line * n + (line % 2 == 0 ? along : n - 1 - along); }
};

// ... with, at node `step_at` (if any), a compass step: the heading off by `step_rad` from there on.
Lawnmower lawnmower(int lines, int n, double sigma_yaw, uint64_t seed, int step_at = -1, double step_rad = 0) {
  Lawnmower s;
  s.n = n;
  for (int l = 0; l < lines; ++l) {
    for (int i = 0; i < n; ++i) {
      const int along = l % 2 == 0 ? i : n - 1 - i;
      s.truth.push_back(pose(20.0 * along, 30.0 * l, l % 2 == 0 ? 0 : M_PI));
    }
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> yaw_noise(0.0, sigma_yaw);
  s.dr = {s.truth[0]};
  for (std::size_t i = 1; i < s.truth.size(); ++i) {
    const double turn = yaw_noise(rng) + (static_cast<int>(i) == step_at ? step_rad : 0.0);
    s.dr.push_back(s.dr.back() * (s.truth[i - 1].inverse() * s.truth[i]) * pose(0, 0, turn) * Eigen::Translation3d(0, 0, 10.0));
  }
  return s;
}

// A registration between adjacent lines at the truth moved by (ex, ey), as an innovation against
// dead reckoning, with the information of a good registration (0.1 m, 0.01 rad).
DrInnovation innovation(const Lawnmower& s, int from, int to, double ex = 0, double ey = 0) {
  PoseGraphEdge edge;
  edge.from = from;
  edge.to = to;
  edge.measured = pose(ex, ey, 0) * Eigen::Translation3d(0, 0, 10.0) * (s.truth[from].inverse() * s.truth[to]);
  edge.information = information_from_sigmas({0.1, 0.1, 0.05}, {0.002, 0.002, 0.01});
  return dr_innovation(edge, DrNoiseModel(s.dr, GraphConfig{}), s.dr);
}

std::vector<DrInnovation> between_lines(const Lawnmower& s, int lines) {
  std::vector<DrInnovation> out;
  for (int l = 0; l + 1 < lines; ++l) {
    for (int i = 1; i < s.n; i += 2) out.push_back(innovation(s, s.node(l, i), s.node(l + 1, i)));
  }
  return out;
}

TEST(NavigationNoise, RecoversTheHeadingNoiseTheNavigationDriftedWith) {
  const double sigma_yaw = 0.003;  // 0.3 of Table 1's 0.01 rad per step
  double log_sum = 0;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    const Lawnmower s = lawnmower(6, 30, sigma_yaw, seed);
    const NavigationNoiseEstimate e = estimate_navigation_noise(s.dr, between_lines(s, 6), GraphConfig{}, {});
    ASSERT_TRUE(e.estimated);
    // One drift's realisation over 180 steps, seen through 75 registrations: within a factor 2,
    // and what the graph gets (the largest scale not ruled out) too.
    const double likeliest = e.likeliest_yaw_scale * GraphConfig{}.dr_sigma_rotation_rad.z();
    EXPECT_GT(likeliest, 0.5 * sigma_yaw) << "seed " << seed;
    EXPECT_LT(e.graph.dr_sigma_rotation_rad.z(), 2.0 * sigma_yaw) << "seed " << seed;
    log_sum += std::log(likeliest / sigma_yaw);
    // No translation noise was added: the estimate leaves Table 1's 5 m far behind.
    EXPECT_LT(e.graph.dr_sigma_translation_m.x(), 0.1) << "seed " << seed;
    EXPECT_EQ(e.graph.dr_sigma_translation_m.z(), GraphConfig{}.dr_sigma_translation_m.z()) << "depth is not estimated";
  }
  EXPECT_LT(std::abs(log_sum / 5), std::log(1.3)) << "over five seeds, within 30 % (geometric mean)";
}

TEST(NavigationNoise, KeepsTableOneWithTooFewRegistrationsOrWhenOff) {
  const Lawnmower s = lawnmower(2, 10, 0.003, 1);
  const std::vector<DrInnovation> all = between_lines(s, 2);
  const std::vector<DrInnovation> few(all.begin(), all.begin() + 2);
  const NavigationNoiseEstimate e = estimate_navigation_noise(s.dr, few, GraphConfig{}, {});
  EXPECT_FALSE(e.estimated);
  EXPECT_EQ(e.graph.dr_sigma_rotation_rad, GraphConfig{}.dr_sigma_rotation_rad);

  const Lawnmower big = lawnmower(6, 30, 0.003, 1);
  NavigationNoiseConfig off;
  off.estimate = false;
  EXPECT_FALSE(estimate_navigation_noise(big.dr, between_lines(big, 6), GraphConfig{}, off).estimated);
}

TEST(NavigationNoise, AFewWrongRegistrationsDoNotPassForANoisyNavigation) {
  const Lawnmower s = lawnmower(6, 30, 0.003, 2);
  std::vector<DrInnovation> innovations = between_lines(s, 6);
  const NavigationNoiseEstimate clean = estimate_navigation_noise(s.dr, innovations, GraphConfig{}, {});
  for (int k = 0; k < 4; ++k) innovations.push_back(innovation(s, s.node(k, 5), s.node(k + 1, 5), 20.0, -15.0));
  const NavigationNoiseEstimate robust = estimate_navigation_noise(s.dr, innovations, GraphConfig{}, {});
  NavigationNoiseConfig plain_config;
  plain_config.outlier_chi2 = 1e6;
  const NavigationNoiseEstimate plain = estimate_navigation_noise(s.dr, innovations, GraphConfig{}, plain_config);
  // Four 25 m outliers among 79: the Cauchy loss keeps them from taking over either sigma.
  EXPECT_LT(robust.graph.dr_sigma_rotation_rad.z(), 1.3 * clean.graph.dr_sigma_rotation_rad.z());
  EXPECT_LT(robust.graph.dr_sigma_translation_m.x(), 2.0 * clean.graph.dr_sigma_translation_m.x());
  EXPECT_GT(plain.graph.dr_sigma_translation_m.x(), 5.0 * clean.graph.dr_sigma_translation_m.x())
      << "the test needs outliers that would inflate a plain likelihood";
}

// Table 1's 5 m per step makes dead reckoning's relative covariance tens of metres wide: a
// registration 8 m off passes its gate. Under the survey's own noise it does not.
TEST(NavigationNoise, TheDrGateUnderTheSurveysNoiseRefusesWhatTableOneLetsBy) {
  const Lawnmower s = lawnmower(6, 30, 0.003, 3);
  const NavigationNoiseEstimate e = estimate_navigation_noise(s.dr, between_lines(s, 6), GraphConfig{}, {});
  const DrInnovation wrong = innovation(s, s.node(2, 10), s.node(3, 10), 8.0, 0.0);
  auto passes = [&](const GraphConfig& graph) {
    const DrNoiseModel dr(s.dr, graph);
    const Covariance6 covariance = dr.covariance(wrong.from, wrong.to) + wrong.measurement;
    return mahalanobis2_xy_yaw(wrong.difference, covariance) <= PlausibilityConfig{}.chi2_threshold;
  };
  EXPECT_TRUE(passes(GraphConfig{}));
  EXPECT_FALSE(passes(e.graph));
  const DrInnovation right = innovation(s, s.node(2, 10), s.node(3, 10));
  const DrNoiseModel dr(s.dr, e.graph);
  EXPECT_LE(mahalanobis2_xy_yaw(right.difference, dr.covariance(right.from, right.to) + right.measurement),
            PlausibilityConfig{}.chi2_threshold);
}

// A compass step of 5 degrees in a navigation otherwise good to 1e-4 rad a step: one white sigma
// small enough for the rest trims every registration across the step, and the DR gate under it
// refuses the right answer there. Modelled as a step of its own, the estimate finds where and how
// large it is, keeps the small sigma, and the gate lets the right answer through.
TEST(NavigationNoise, ACompassStepIsFoundWhereTheRegistrationsAcrossItAgree) {
  const double step = 5.0 * M_PI / 180;
  const Lawnmower s = lawnmower(6, 30, 1e-4, 4, 80, step);  // node 80: line 2, 20 submaps along
  const std::vector<DrInnovation> innovations = between_lines(s, 6);
  const NavigationNoiseEstimate e = estimate_navigation_noise(s.dr, innovations, GraphConfig{}, {});
  ASSERT_EQ(e.heading_steps.size(), 1u);
  EXPECT_NEAR(e.heading_steps[0].step, 79, 1) << "the odometry step into node 80";
  EXPECT_NEAR(std::abs(e.heading_steps[0].jump_rad), step, 0.1 * step);
  EXPECT_GE(e.heading_steps[0].explained, 3);
  EXPECT_LT(e.graph.dr_sigma_rotation_rad.z(), 1e-3) << "the rest of the navigation stays stiff";

  NavigationNoiseConfig white;
  white.max_heading_steps = 0;
  const NavigationNoiseEstimate without = estimate_navigation_noise(s.dr, innovations, GraphConfig{}, white);
  const DrInnovation right = innovation(s, s.node(2, 25), s.node(3, 25));  // from after the step to the next line
  const DrInnovation across = innovation(s, s.node(1, 25), s.node(2, 25));  // from before it to after
  auto passes = [&](const GraphConfig& graph, const DrInnovation& i) {
    const DrNoiseModel dr(s.dr, graph);
    return mahalanobis2_xy_yaw(i.difference, dr.covariance(i.from, i.to) + i.measurement) <= PlausibilityConfig{}.chi2_threshold;
  };
  EXPECT_TRUE(passes(e.graph, across));
  EXPECT_FALSE(passes(without.graph, across)) << "the test needs a step the white sigma cannot take";
  EXPECT_TRUE(passes(e.graph, right));

  // Without a step, none is found.
  const Lawnmower clean = lawnmower(6, 30, 1e-4, 4);
  EXPECT_TRUE(estimate_navigation_noise(clean.dr, between_lines(clean, 6), GraphConfig{}, {}).heading_steps.empty());
}

// Five registrations between two short lines of a heading walk: the likeliest heading noise is
// under half the true one on many seeds. The graph gets the loosest heading the innovations do
// not rule out, so the true noise is within what it allows on nearly every seed.
TEST(NavigationNoise, WhatFewRegistrationsCannotRuleOutStaysAllowed) {
  const double sigma_yaw = 0.003;
  int likeliest_below = 0, published_below = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    const Lawnmower s = lawnmower(2, 10, sigma_yaw, seed);
    const NavigationNoiseEstimate e = estimate_navigation_noise(s.dr, between_lines(s, 2), GraphConfig{}, {});
    ASSERT_TRUE(e.estimated);
    const double prior_yaw = GraphConfig{}.dr_sigma_rotation_rad.z();
    likeliest_below += e.likeliest_yaw_scale * prior_yaw < sigma_yaw / 2;
    published_below += e.graph.dr_sigma_rotation_rad.z() < sigma_yaw / 2;
    EXPECT_GE(e.yaw_scale, e.likeliest_yaw_scale);
  }
  // Measured: the likeliest under half the truth on 9 of 20 seeds, the published on 2 (a 95 %
  // bound from five innovations).
  EXPECT_LE(published_below, 2) << "of 20 seeds, the graph's heading noise under half the true";
  EXPECT_GE(likeliest_below, 5) << "the test needs seeds whose likeliest heading noise is too stiff";
}

// Registrations that agree with dead reckoning exactly put the likeliest heading noise at its
// least scale: they show no drift, which is no evidence that dead reckoning rules aliases out, so
// aliases are judged under the loosest heading not ruled out. Where the innovations show a drift,
// its likeliest noise judges them, as before.
TEST(NavigationNoise, AliasesAreJudgedUnderTheLikeliestHeadingOnlyWhereTheDataDetermineIt) {
  const NavigationNoiseConfig config;
  const Lawnmower straight = lawnmower(2, 10, 0.0, 1);  // dead reckoning without heading drift
  const NavigationNoiseEstimate calm = estimate_navigation_noise(straight.dr, between_lines(straight, 2), GraphConfig{}, config);
  ASSERT_TRUE(calm.estimated);
  ASSERT_NEAR(calm.likeliest_yaw_scale, config.min_scale, 1e-12) << "the likelihood's maximum at its bound";
  ASSERT_GT(calm.yaw_scale, 10 * calm.likeliest_yaw_scale) << "what few innovations do not rule out";
  EXPECT_EQ(alias_graph(calm, config).dr_sigma_rotation_rad, calm.graph.dr_sigma_rotation_rad);

  const Lawnmower walk = lawnmower(6, 30, 0.003, 1);
  const NavigationNoiseEstimate drift = estimate_navigation_noise(walk.dr, between_lines(walk, 6), GraphConfig{}, config);
  ASSERT_GT(drift.likeliest_yaw_scale, 10 * config.min_scale);
  EXPECT_EQ(alias_graph(drift, config).dr_sigma_rotation_rad, drift.likeliest_graph.dr_sigma_rotation_rad);
}

}  // namespace
}  // namespace bathyslam
