// The pipeline's defences against wrong edges, on constraints built by hand: the DR gate, the
// consistency selection, and the safety net that checks a solution before it is published.
#include "core/pipeline/robust_backend.h"
#include "core/pipeline/pipeline.h"
#include "core/pipeline/safety_net.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/unit/submap_errors.h"
#include "tests/unit/true_submaps.h"

namespace bathyslam {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Isometry3d pose(double x, double y, double yaw) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = Eigen::Vector3d(x, y, -10.0);
  p.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return p;
}

// Two lines of `n` submaps, 20 m apart along the line, 30 m between the lines (east, then back
// west), with dead reckoning that drifts in yaw; odometry constraints carry Table 1's DR noise.
struct Survey2Lines {
  std::vector<Eigen::Isometry3d> truth;
  PipelineResult result;
};

Survey2Lines two_lines(int n, uint64_t seed) {
  Survey2Lines s;
  for (int i = 0; i < n; ++i) s.truth.push_back(pose(20.0 * i, 0, 0));
  for (int i = n - 1; i >= 0; --i) s.truth.push_back(pose(20.0 * i, 30.0, M_PI));
  PipelineResult& r = s.result;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> yaw_noise(0.0, 0.006);
  r.dr_poses = {s.truth[0]};
  for (std::size_t i = 1; i < s.truth.size(); ++i) {
    r.dr_poses.push_back(r.dr_poses.back() * (s.truth[i - 1].inverse() * s.truth[i]) * pose(0, 0, yaw_noise(rng)) *
                         Eigen::Translation3d(0, 0, 10.0));
  }
  for (std::size_t i = 0; i < s.truth.size(); ++i) {
    Submap m;
    m.index = static_cast<int>(i);
    m.line = static_cast<int>(i) < n ? 0 : 1;
    r.submaps.submaps.push_back(m);
  }
  r.constraints = odometry_constraints(r.dr_poses, r.config.graph);
  return s;
}

// A registration between two submaps: the truth moved by `error` (x, y, yaw), with the
// information of a good feature-aided registration.
Constraint registration(const Survey2Lines& s, int from, int to, double ex = 0, double ey = 0, double eyaw = 0) {
  Constraint c;
  c.type = ConstraintType::kLoop;
  c.from = from;
  c.to = to;
  c.path = RegistrationPath::kFeatureAided;
  c.measured = pose(ex, ey, eyaw) * Eigen::Translation3d(0, 0, 10.0) * (s.truth[from].inverse() * s.truth[to]);
  c.information = information_from_sigmas({0.1, 0.1, 0.05}, {0.002, 0.002, 0.004});
  return c;
}

double max_error(const std::vector<Eigen::Isometry3d>& poses, const std::vector<Eigen::Isometry3d>& truth) {
  double e = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) e = std::max(e, (poses[i].translation() - truth[i].translation()).norm());
  return e;
}

TEST(DrGate, RefusesARegistrationTurnedFarBeyondWhatDeadReckoningCanDriftAndKeepsTheTruth) {
  const Survey2Lines s = two_lines(20, 1);
  const DrNoiseModel dr(s.result.dr_poses, GraphConfig{});
  Constraint good = registration(s, 5, 34), turned = registration(s, 5, 34, 3.0, -2.0, 120 * kDeg);
  gate_against_dead_reckoning(good, dr, s.result.dr_poses, PlausibilityConfig{});
  gate_against_dead_reckoning(turned, dr, s.result.dr_poses, PlausibilityConfig{});
  EXPECT_TRUE(good.accepted()) << good.rejection.text();
  EXPECT_LT(good.dr_mahalanobis2, 16.27);
  EXPECT_FALSE(turned.accepted());
  EXPECT_GT(turned.dr_mahalanobis2, 100.0);
  EXPECT_EQ(turned.rejection.kind, RejectionKind::kImplausible) << turned.rejection.text();
}

TEST(ConsistencySelection, LeavesOutTheRegistrationsThatDisagreeAndNeverTouchesDepthOnlyEdges) {
  Survey2Lines s = two_lines(20, 2);
  std::vector<Constraint>& constraints = s.result.constraints;
  for (int i = 2; i < 18; i += 3) constraints.push_back(registration(s, i, 39 - i));      // agree
  constraints.push_back(registration(s, 4, 34, 12.0, 5.0, 10 * kDeg));                     // wrong
  constraints.push_back(registration(s, 9, 31, -15.0, 0.0, -8 * kDeg));                    // wrong
  Constraint depth_only = registration(s, 10, 29, 25.0, 25.0, 0.0);  // far off, but only depth
  for (int k : {0, 1, 5}) depth_only.information(k, k) = 0;
  depth_only.path = RegistrationPath::kDirect;
  constraints.push_back(depth_only);

  const DrNoiseModel dr(s.result.dr_poses, GraphConfig{});
  select_consistent_registrations(constraints, dr, s.result.dr_poses, LoopConsistencyConfig{});
  const std::size_t n = constraints.size();
  for (std::size_t k = n - 9; k < n - 3; ++k) EXPECT_TRUE(constraints[k].in_graph()) << k << ": " << constraints[k].exclusion.text();
  EXPECT_FALSE(constraints[n - 3].in_graph());
  EXPECT_FALSE(constraints[n - 2].in_graph());
  EXPECT_EQ(constraints[n - 2].exclusion.kind, RejectionKind::kInconsistent);
  EXPECT_TRUE(constraints[n - 1].in_graph()) << "an edge without horizontal information cannot bend the survey";
}

// The safety net over `constraints` on the survey's lines, with the survey's noise model.
Publication safety_net_on(const Survey2Lines& s, std::vector<Constraint>& constraints,
                          const PipelineConfig::Robustness& robustness = PipelineConfig{}.robustness) {
  std::vector<int> lines;
  for (const Submap& m : s.result.submaps.submaps) lines.push_back(m.line);
  return solve_with_safety_net(s.result.dr_poses, lines, constraints, s.result.navigation_noise.graph, robustness);
}

// A wrong edge with the information of a good one, forced past the front end's tests: the
// safety net finds it pulling against the solution, drops it, and the published trajectory is
// the one the good edges give.
TEST(SafetyNet, DropsAConfidentlyWrongEdgeAndPublishesWhatTheGoodEdgesGive) {
  Survey2Lines s = two_lines(20, 3);
  for (int i = 1; i < 19; i += 2) s.result.constraints.push_back(registration(s, i, 39 - i));
  std::vector<Constraint> good = s.result.constraints;
  const Publication good_solution = safety_net_on(s, good);
  ASSERT_TRUE(good_solution.safety_net.pass) << good_solution.safety_net.verdict;
  EXPECT_TRUE(good_solution.safety_net.dropped.empty());

  s.result.constraints.push_back(registration(s, 6, 30, 20.0, -10.0, 90 * kDeg));
  const GraphSolution unchecked = solve(s.result.dr_poses, s.result.constraints, s.result.config.graph);
  std::vector<Constraint> checked = s.result.constraints;
  const Publication checked_solution = safety_net_on(s, checked);

  EXPECT_TRUE(checked_solution.safety_net.pass) << checked_solution.safety_net.verdict;
  ASSERT_EQ(checked_solution.safety_net.dropped.size(), 1u);
  EXPECT_NE(checked_solution.safety_net.dropped[0].find("6->30"), std::string::npos) << checked_solution.safety_net.dropped[0];
  EXPECT_FALSE(checked.back().in_graph());
  EXPECT_EQ(checked.back().exclusion.kind, RejectionKind::kSafetyNet);
  EXPECT_NEAR(max_error(checked_solution.graph.poses, s.truth), max_error(good_solution.graph.poses, s.truth), 1e-6);
  EXPECT_GT(max_error(unchecked.poses, s.truth), max_error(good_solution.graph.poses, s.truth) + 1.0)
      << "the test needs a wrong edge that does harm";
}

// Edges that all agree on a wrong answer bend both lines; when dropping up to `max_drops` of
// them does not give a solution within DR's noise, dead reckoning is published.
TEST(SafetyNet, FallsBackToDeadReckoningWhenNoSolutionPasses) {
  Survey2Lines s = two_lines(20, 4);
  for (int i = 1; i < 19; ++i) s.result.constraints.push_back(registration(s, i, 39 - i, 0.0, 0.0, 25 * kDeg));
  PipelineConfig::Robustness robustness;
  robustness.max_drops = 3;
  const Publication published = safety_net_on(s, s.result.constraints, robustness);
  EXPECT_FALSE(published.safety_net.pass);
  EXPECT_TRUE(published.safety_net.fell_back);
  EXPECT_EQ(published.safety_net.dropped.size(), 3u);
  EXPECT_NE(published.safety_net.verdict.find("published dead reckoning"), std::string::npos);
  for (std::size_t i = 0; i < s.truth.size(); ++i) EXPECT_TRUE(published.graph.poses[i].isApprox(s.result.dr_poses[i]));
  for (const Constraint& c : s.result.constraints) {
    if (from_navigation(c.type)) continue;
    EXPECT_FALSE(c.in_graph()) << "the report's accepted edges are the published map's";
  }
}

// A graph solved again after the safety net had dropped edges (the change discount): the verdict
// of a pass counts both solves' drops, the first solve's listed first; a failure keeps its words.
TEST(SafetyNet, ASecondSolveCountsTheFirstOnesDrops) {
  SafetyNet earlier;
  earlier.dropped = {"loop 3->40: pulled 7.0 sigma", "loop 5->38: pulled 6.5 sigma"};
  SafetyNet passed;
  passed.pass = true;
  passed.verdict = "pass: every line within dead reckoning's noise";
  passed.dropped = {"loop 9->31: pulled 6.2 sigma"};
  count_earlier_drops(passed, earlier);
  ASSERT_EQ(passed.dropped.size(), 3u);
  EXPECT_EQ(passed.dropped.front(), earlier.dropped.front());
  EXPECT_EQ(passed.verdict, "pass after dropping 3 registrations");

  SafetyNet failed;
  failed.pass = false;
  failed.verdict = "FAILED after dropping 0 registrations: published dead reckoning instead";
  count_earlier_drops(failed, earlier);
  EXPECT_EQ(failed.dropped.size(), 2u);
  EXPECT_EQ(failed.verdict, "FAILED after dropping 0 registrations: published dead reckoning instead");
}

// Consistency reports by hand: dead reckoning's and the solved map's RMSE and p99 (m), and the
// bound dead reckoning's p99 could reach by the sampling of its cells alone.
std::pair<ConsistencyReport, ConsistencyReport> maps(double dr_rmse, double dr_p99, double dr_p99_upper, double rmse,
                                                     double p99) {
  ConsistencyReport dr, solved;
  dr.stats.rmse = dr_rmse, dr.stats.p99 = dr_p99, dr.p99_upper = dr_p99_upper;
  solved.stats.rmse = rmse, solved.stats.p99 = p99;
  return {dr, solved};
}

// A solution whose map agrees with itself less than dead reckoning's is not published, whatever
// the graph said; one that agrees better is.
TEST(SafetyNet, PublishesDeadReckoningWhenTheSolvedMapIsLessConsistent) {
  const Survey2Lines s = two_lines(10, 5);
  const PipelineConfig config;
  const auto [dr, better] = maps(0.30, 0.90, 0.0, 0.10, 0.40);
  EXPECT_FALSE(less_consistent_than_dead_reckoning(better, dr, s.result.submaps, s.result.dr_poses, config));

  const auto [same_dr, tail] = maps(0.30, 0.90, 0.0, 0.10, 1.20);  // better on the whole, worse in the tail
  const auto why = less_consistent_than_dead_reckoning(tail, same_dr, s.result.submaps, s.result.dr_poses, config);
  ASSERT_TRUE(why) << "not supported";
  EXPECT_NE(why->find("published dead reckoning"), std::string::npos);

  // What the evaluation does with that verdict: the solved map published when supported,
  // dead reckoning (its poses, its map's report, every registration out) when not.
  std::vector<Constraint> constraints = s.result.constraints;
  constraints.push_back(registration(s, 3, 16));
  Publication kept{{s.truth}, {}};
  ConsistencyReport kept_map = better;
  EXPECT_FALSE(fall_back_unless_more_consistent(kept, kept_map, dr, s.result.submaps, s.result.dr_poses, constraints, config));
  EXPECT_TRUE(kept.graph.poses[5].isApprox(s.truth[5]));
  EXPECT_DOUBLE_EQ(kept_map.stats.rmse, 0.10);
  EXPECT_TRUE(constraints.back().in_graph());

  Publication published{{s.truth}, {}};
  ConsistencyReport published_map = tail;
  EXPECT_TRUE(fall_back_unless_more_consistent(published, published_map, same_dr, s.result.submaps, s.result.dr_poses,
                                               constraints, config));
  EXPECT_TRUE(published.safety_net.fell_back);
  EXPECT_FALSE(published.safety_net.pass);
  EXPECT_EQ(published.safety_net.verdict, *why);
  for (std::size_t i = 0; i < s.truth.size(); ++i) EXPECT_TRUE(published.graph.poses[i].isApprox(s.result.dr_poses[i]));
  EXPECT_DOUBLE_EQ(published_map.stats.rmse, 0.30) << "the report is dead reckoning's map's";
  EXPECT_EQ(constraints.back().exclusion.kind, RejectionKind::kSafetyNet);
  EXPECT_TRUE(constraints.front().in_graph()) << "dead reckoning's own odometry stays";
}

// The solved map is judged as a whole (robustness.publish_rule 1, each cell its own sample): a p99 a little above dead
// reckoning's but within what the sampling of its cells allows does not throw away a map whose
// RMSE fell by a third; beyond that bound, or under the old rule, dead reckoning is published.
TEST(SafetyNet, ToleratesAP99RiseWithinDeadReckoningsOwnSamplingNoise) {
  const Survey2Lines s = two_lines(10, 6);
  PipelineConfig whole;
  whole.robustness.publish_rule = 1;
  const auto [dr, solved] = maps(0.30, 0.90, 0.97, 0.20, 0.93);
  const auto& submaps = s.result.submaps;
  const auto& dr_poses = s.result.dr_poses;
  const auto verdict = less_consistent_than_dead_reckoning(solved, dr, submaps, dr_poses, whole);
  EXPECT_FALSE(verdict) << *verdict;

  PipelineConfig old_rule;
  old_rule.robustness.publish_rule = 0;
  EXPECT_TRUE(less_consistent_than_dead_reckoning(solved, dr, submaps, dr_poses, old_rule));

  const auto [same_dr, beyond] = maps(0.30, 0.90, 0.97, 0.20, 1.00);
  const auto why = less_consistent_than_dead_reckoning(beyond, same_dr, submaps, dr_poses, whole);
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("sampling noise"), std::string::npos) << *why;
}

// A map whose every submap is a little off (each its own pose error) has a p99 that another map
// of the same quality could exceed by far more than the cells' own sampling says, because a
// submap's cells move together (robustness.publish_rule 2, p99_upper_by_blocks). A solved map
// whose RMSE fell and whose p99 rose within that is published; rule 1 refused it. A map with a
// blunder (one submap a metre off) is refused by every rule.
TEST(SafetyNet, WeighsTheP99RiseByTheSubmapsNotTheCells) {
  const PipelineConfig by_blocks;
  const SubmapSet submaps = lines_with_submap_errors(0.1, 0.02, 1);
  const std::vector<Eigen::Isometry3d> dr_poses = poses_of(submaps);
  const ConsistencyReport dr = consistency_error(submaps, dr_poses, by_blocks.consistency);
  const double blocks = p99_upper_by_blocks(submaps, dr_poses, by_blocks.consistency, median_submap_side_m(submaps));
  ASSERT_GT(blocks, dr.p99_upper);
  ConsistencyReport solved;
  solved.stats.rmse = 0.8 * dr.stats.rmse;
  solved.stats.p99 = (dr.p99_upper + blocks) / 2;

  const auto verdict = less_consistent_than_dead_reckoning(solved, dr, submaps, dr_poses, by_blocks);
  EXPECT_FALSE(verdict) << *verdict;
  PipelineConfig by_cells;
  by_cells.robustness.publish_rule = 1;
  EXPECT_TRUE(less_consistent_than_dead_reckoning(solved, dr, submaps, dr_poses, by_cells));

  // Its bound is dead reckoning's map's: the blunder's own map, drawn in blocks, would allow it.
  std::vector<Eigen::Isometry3d> blunder_poses = dr_poses;
  blunder_poses[40].translation().z() += 1.0;
  ConsistencyReport blunder = consistency_error(submaps, blunder_poses, by_blocks.consistency);
  blunder.stats.rmse = 0.8 * dr.stats.rmse;  // a better map elsewhere
  const auto why = less_consistent_than_dead_reckoning(blunder, dr, submaps, dr_poses, by_blocks);
  ASSERT_TRUE(why);
  EXPECT_NE(why->find("sampling noise"), std::string::npos) << *why;
}

// A probe result by hand: the answer fits at 1e-3 m², and every offset in `competing` fits
// nearly as well (a 49 x 49 square of offsets 1 m apart).
// An offset's bit in a probe of reach 24, 1 m apart (Uniqueness::competitors' layout).
std::size_t probe_bit(const Eigen::Vector2d& o) { return static_cast<std::size_t>((o.y() + 24) * 49 + (o.x() + 24)); }

Uniqueness probed_with(const std::vector<Eigen::Vector2d>& competing) {
  Uniqueness u;
  u.probed = true;
  u.cost_at_answer_m2 = u.nearby_cost_m2 = 1e-3;
  u.reach = 24;
  u.step_m = 1.0;
  u.competitors.assign(49 * 49, false);
  for (const Eigen::Vector2d& o : competing) {
    u.competitors[probe_bit(o)] = true;
  }
  u.alternative_cost_m2 = 2e-3;
  return u;
}

// Marks `open` (competitors already) as running on past what the probe compared.
void mark_open(Uniqueness& u, const std::vector<Eigen::Vector2d>& open) {
  u.open_competitors.assign(u.competitors.size(), false);
  for (const Eigen::Vector2d& o : open) u.open_competitors[probe_bit(o)] = true;
}

// A crest along x: every offset on it from 3 m out to the probe's overlap's end at |x| = 20 fits.
std::vector<Eigen::Vector2d> crest_along_x() {
  std::vector<Eigen::Vector2d> along_crest;
  for (int x = -20; x <= 20; ++x) {
    if (std::abs(x) >= 3) along_crest.emplace_back(x, 0);
  }
  return along_crest;
}

// Sand waves 10 m apart, crests along y: the terrain also fits 10 and 20 m away across them.
std::vector<Eigen::Vector2d> sand_wave_aliases() { return {{-20, 0}, {-10, 0}, {10, 0}, {20, 0}}; }

Constraint direct_registration(const Survey2Lines& s, int from, int to, const Uniqueness& u) {
  Constraint c = registration(s, from, to);
  c.type = ConstraintType::kAdjacent;
  c.path = RegistrationPath::kDirect;
  c.uniqueness = u;
  return c;
}

// Nine DR steps of 0.006 rad (the fixture's own heading noise) keep the pair within about a metre
// and a half: aliases 10 m away are ruled out. Table 1's 5 m a step cannot rule them out.
GraphConfig survey_noise() {
  GraphConfig g;
  g.dr_sigma_translation_m = {0.01, 0.01, 1.0};
  g.dr_sigma_rotation_rad = {1e-4, 1e-4, 0.006};
  return g;
}

TEST(AliasFromPrior, ADirectAnswerAcrossSandWavesKeepsItsInformationWhenDeadReckoningRulesTheAliasesOut) {
  const Survey2Lines s = two_lines(20, 7);
  Constraint c = direct_registration(s, 15, 24, probed_with(sand_wave_aliases()));
  const Information6 before = c.information;
  resolve_alias(c, DrNoiseModel(s.result.dr_poses, survey_noise()), s.result.dr_poses, 25.0, PlausibilityConfig{},
                Eigen::Matrix3d::Identity());
  EXPECT_TRUE(c.accepted());
  EXPECT_EQ(c.alias, AliasResolution::kRuledOut);
  EXPECT_GT(c.alias_mahalanobis2, PlausibilityConfig{}.chi2_threshold);
  EXPECT_TRUE(c.information.isApprox(before));
}

TEST(AliasFromPrior, ADirectAnswerLosesItsHorizontalInformationWhereDeadReckoningAllowsAnAlias) {
  const Survey2Lines s = two_lines(20, 7);
  Constraint c = direct_registration(s, 15, 24, probed_with(sand_wave_aliases()));
  resolve_alias(c, DrNoiseModel(s.result.dr_poses, GraphConfig{}), s.result.dr_poses, 25.0, PlausibilityConfig{},
                Eigen::Matrix3d::Identity());
  EXPECT_TRUE(c.accepted());
  EXPECT_EQ(c.alias, AliasResolution::kInformationRemoved);
  for (int k : {0, 1, 5}) EXPECT_NEAR(c.information(k, k), 0.0, 1e-9) << k;
  EXPECT_GT(c.information(2, 2), 50.0) << "depth stays";
  EXPECT_NEAR(c.alias_spread_m.x(), std::sqrt((400 + 100 + 100 + 400) / 4.0), 1e-9) << "the aliases' line, reported";

  // Competitors all around (a weakly textured patch): nothing horizontal is known.
  std::vector<Eigen::Vector2d> around;
  for (int x = -6; x <= 6; ++x) {
    for (int y = -6; y <= 6; ++y) {
      if (std::hypot(x, y) >= 3) around.emplace_back(x, y);
    }
  }
  Constraint patch = direct_registration(s, 15, 24, probed_with(around));
  resolve_alias(patch, DrNoiseModel(s.result.dr_poses, GraphConfig{}), s.result.dr_poses, 25.0, PlausibilityConfig{},
                Eigen::Matrix3d::Identity());
  for (int k : {0, 1, 5}) EXPECT_NEAR(patch.information(k, k), 0.0, 1e-9) << k;
  EXPECT_GT(patch.information(2, 2), 50.0) << "depth stays";
}

TEST(AliasFromPrior, AFeatureAidedAnswerIsRefusedOnlyWhereDeadReckoningAllowsAnAlias) {
  const Survey2Lines s = two_lines(20, 7);
  Constraint loose = registration(s, 15, 24), tight = registration(s, 15, 24);
  loose.uniqueness = tight.uniqueness = probed_with(sand_wave_aliases());
  resolve_alias(loose, DrNoiseModel(s.result.dr_poses, GraphConfig{}), s.result.dr_poses, 25.0, PlausibilityConfig{},
                Eigen::Matrix3d::Identity());
  resolve_alias(tight, DrNoiseModel(s.result.dr_poses, survey_noise()), s.result.dr_poses, 25.0, PlausibilityConfig{},
                Eigen::Matrix3d::Identity());
  EXPECT_EQ(loose.rejection.kind, RejectionKind::kNotUnique) << loose.rejection.text();
  EXPECT_TRUE(tight.accepted()) << tight.rejection.text();
  EXPECT_EQ(tight.alias, AliasResolution::kRuledOut);

  Constraint unprobed = registration(s, 15, 24);
  resolve_alias(unprobed, DrNoiseModel(s.result.dr_poses, survey_noise()), s.result.dr_poses, 25.0, PlausibilityConfig{},
                Eigen::Matrix3d::Identity());
  EXPECT_EQ(unprobed.rejection.kind, RejectionKind::kNotUnique) << "too little overlap to probe";
}

// A feature-aided answer along a line of aliases that dead reckoning does not rule out, judged as a
// direct answer there would be (quality.feature_aliases_as_direct): its position across the line
// stays, with its turn marginalised out, nothing along the line, no yaw, and no more depth than the
// relief allows; refused without.
TEST(AliasFromPrior, AFeatureAidedAnswerAmongPlausibleAliasesKeepsWhatADirectOneWould) {
  const Survey2Lines s = two_lines(20, 7);
  Uniqueness crest = probed_with(crest_along_x());
  crest.alternative_cost_m2 = 10 * crest.cost_at_answer_m2;  // another basin clearly worse
  crest.local_cost_m2 = 0.01;                                // relief: depth to 0.1 m at best
  const DrNoiseModel table1(s.result.dr_poses, GraphConfig{});
  Constraint judged = registration(s, 15, 24), refused = registration(s, 15, 24);
  judged.uniqueness = refused.uniqueness = crest;
  // The answer's y and its turn measured together: y alone is known less well than its 0.1 m.
  judged.information(1, 5) = judged.information(5, 1) = 0.5 * std::sqrt(judged.information(1, 1) * judged.information(5, 5));
  const double y_given_any_turn = judged.information(1, 1) - judged.information(1, 5) * judged.information(1, 5) / judged.information(5, 5);
  resolve_alias(judged, table1, s.result.dr_poses, 25.0, PlausibilityConfig{}, Eigen::Matrix3d::Identity(),
                AliasRule{true, 2.0, true, true});
  resolve_alias(refused, table1, s.result.dr_poses, 25.0, PlausibilityConfig{}, Eigen::Matrix3d::Identity(),
                AliasRule{true, 2.0, false, true});
  EXPECT_EQ(refused.rejection.kind, RejectionKind::kNotUnique) << refused.rejection.text();
  ASSERT_TRUE(judged.accepted()) << judged.rejection.text();
  EXPECT_EQ(judged.alias, AliasResolution::kInformationRemoved);
  EXPECT_GT(judged.alias_spread_m.x(), 10.0) << "the aliases' line, reported";
  EXPECT_NEAR(judged.information(1, 1), y_given_any_turn, 1.0) << "across the line: y whatever the turn (75, not 100)";
  EXPECT_LT(judged.information(0, 0), 0.02) << "along it: no better than the aliases' spread";
  EXPECT_NEAR(judged.information(5, 5), 0.0, 1e-12) << "no yaw: a competitor's turn is not the answer's";
  EXPECT_NEAR(judged.information(2, 2), 100.0, 1e-6) << "depth as the relief allows, not its own 400";
}

// A direct answer turned far beyond what dead reckoning's heading noise allows keeps no horizontal
// information (quality.max_turn_chi2): the DR gate cannot see the turn, the answer keeping no yaw.
TEST(DrGate, ADirectAnswerTurnedBeyondTheHeadingNoiseKeepsNoPosition) {
  const Survey2Lines s = two_lines(20, 7);
  const DrNoiseModel survey(s.result.dr_poses, survey_noise());
  const Eigen::Vector2d unique_far_away(23, 23);  // one competitor, ruled out by dead reckoning
  PipelineConfig config;
  const Plan plan = plan_of(config);
  // The pair's truth turned by `turn_deg`, with a direct answer's information (no roll, pitch, yaw).
  const auto turned = [&](double turn_deg) {
    Constraint c = direct_registration(s, 15, 24, probed_with({unique_far_away}));
    c.measured = pose(0, 0, turn_deg * kDeg) * c.measured;
    for (int k : {3, 4, 5}) c.information.row(k).setZero(), c.information.col(k).setZero();
    c.registered_information = c.information;
    return c;
  };
  for (const double turn_deg : {0.5, 6.0}) {
    Constraint c = turned(turn_deg);
    judge_with_prior(c, survey, survey, s.result.dr_poses, config, plan);
    ASSERT_TRUE(c.accepted()) << turn_deg << ": " << c.rejection.text();
    if (turn_deg < 1) {
      EXPECT_GT(c.information(1, 1), 50.0) << "a turn within the heading noise (0.02 rad over 9 steps)";
    } else {
      EXPECT_NEAR(c.information(0, 0), 0.0, 1e-12) << "turned 6 degrees: no position";
      EXPECT_NEAR(c.information(1, 1), 0.0, 1e-12);
      EXPECT_GT(c.information(2, 2), 50.0) << "depth stays";
    }
  }
  Constraint untested = turned(6.0);
  config.quality.max_turn_chi2 = 0;
  judge_with_prior(untested, survey, survey, s.result.dr_poses, config, plan);
  EXPECT_GT(untested.information(1, 1), 50.0) << "not tested";

  // Nor without the DR gate (the `gicp` baseline's plan): the paper's method stays as it was.
  Constraint baseline = turned(6.0);
  const PipelineConfig gicp = preset_config(Configuration::kGicp);
  judge_with_prior(baseline, survey, survey, s.result.dr_poses, gicp, plan_of(gicp));
  EXPECT_GT(baseline.information(1, 1), 50.0) << "no DR gate, no turn test";
}

// With doubt_widens, the same answer along a line of plausible aliases keeps its position across
// the line, as well as the line is narrow, and nothing along it where the line runs on past
// what the probe compared; a patch whose competitors run on every way keeps nothing.
TEST(AliasFromPrior, WideningKeepsTheDirectAnswersPositionAcrossALineOfAliases) {
  const Survey2Lines s = two_lines(20, 7);
  // Crests along x: the aliases lie along x, the probe's overlap ending at |x| = 20.
  Uniqueness crest = probed_with(crest_along_x());
  Constraint closed = direct_registration(s, 15, 24, crest);
  resolve_alias(closed, DrNoiseModel(s.result.dr_poses, GraphConfig{}), s.result.dr_poses, 25.0, PlausibilityConfig{},
                Eigen::Matrix3d::Identity(), AliasRule{true});
  EXPECT_EQ(closed.alias, AliasResolution::kInformationRemoved);
  EXPECT_NEAR(closed.information(1, 1), 100.0, 1.0) << "across the line: the answer's own 0.1 m";
  EXPECT_GT(closed.information(0, 0), 0.0);
  EXPECT_LT(closed.information(0, 0), 0.02) << "along it: no better than the aliases' spread, 12 m";
  EXPECT_NEAR(closed.information(5, 5), 0.0, 1e-12) << "no yaw";
  EXPECT_GT(closed.information(2, 2), 50.0) << "depth stays";

  mark_open(crest, {{-20, 0}, {20, 0}});
  Constraint open = direct_registration(s, 15, 24, crest);
  resolve_alias(open, DrNoiseModel(s.result.dr_poses, GraphConfig{}), s.result.dr_poses, 25.0, PlausibilityConfig{},
                Eigen::Matrix3d::Identity(), AliasRule{true});
  EXPECT_NEAR(open.information(0, 0), 0.0, 1e-9) << "the line runs on: nothing along it";
  EXPECT_NEAR(open.information(1, 1), 100.0, 1.0);

  std::vector<Eigen::Vector2d> around, rim;
  for (int x = -6; x <= 6; ++x) {
    for (int y = -6; y <= 6; ++y) {
      if (std::hypot(x, y) >= 3) around.emplace_back(x, y);
      if (std::max(std::abs(x), std::abs(y)) == 6) rim.emplace_back(x, y);
    }
  }
  Uniqueness patch_probe = probed_with(around);
  mark_open(patch_probe, rim);
  Constraint patch = direct_registration(s, 15, 24, patch_probe);
  resolve_alias(patch, DrNoiseModel(s.result.dr_poses, GraphConfig{}), s.result.dr_poses, 25.0, PlausibilityConfig{},
                Eigen::Matrix3d::Identity(), AliasRule{true});
  for (int k : {0, 1, 5}) EXPECT_NEAR(patch.information(k, k), 0.0, 1e-9) << k;
}

// Widening along the crest line trusts dead reckoning to have ruled out every basin off the line:
// where the best of them fits nearly as well as the answer, the answer may itself be that basin's
// alias (on `small` sand waves and channels, loops 2-14 m off), and keeps nothing horizontal.
TEST(AliasFromPrior, WideningNeedsTheAnswerToFitClearlyBetterThanAnyOtherBasin) {
  const Survey2Lines s = two_lines(20, 7);
  Uniqueness crest = probed_with(crest_along_x());
  const double min_distinctness = QualityConfig{}.widen_min_distinctness;
  ASSERT_GT(min_distinctness, 1.0);
  for (const double distinctness : {0.9, 0.99 * min_distinctness, 1.01 * min_distinctness, 4.0}) {
    crest.alternative_cost_m2 = distinctness * crest.cost_at_answer_m2;
    Constraint c = direct_registration(s, 15, 24, crest);
    resolve_alias(c, DrNoiseModel(s.result.dr_poses, GraphConfig{}), s.result.dr_poses, 25.0, PlausibilityConfig{},
                  Eigen::Matrix3d::Identity(), AliasRule{true, min_distinctness});
    EXPECT_EQ(c.alias, AliasResolution::kInformationRemoved);
    EXPECT_GT(c.information(2, 2), 50.0) << "depth stays";
    if (distinctness < min_distinctness) {
      for (int k : {0, 1, 5}) EXPECT_NEAR(c.information(k, k), 0.0, 1e-9) << distinctness << " " << k;
    } else {
      EXPECT_NEAR(c.information(1, 1), 100.0, 1.0) << distinctness << ": across the line, the answer's own 0.1 m";
    }
  }
}

// GICP, started 1.06 m aside on both diagonals, comes back across the crests (y) but stays where
// it started along them (x): only the position across stays, widened by how far the landings
// fell from the answer.
TEST(DoubtWidens, KeepsOnlyTheDirectionGicpComesBackAlong) {
  const Information6 own = information_from_sigmas({0.05, 0.05, 0.05}, {0.002, 0.002, 0.004});
  OtherAnswers others;
  const double d = 1.5 / std::sqrt(2.0);
  others.shifts = {{d, d}, {-d, d}};
  others.landings = {{d, 0.3}, {-d, -0.3}};
  Eigen::Matrix2d spread;
  const Information6 widened = widened_by_doubt(own, others, spread);
  EXPECT_NEAR(widened(0, 0), 0.0, 1e-9) << "along the crests: where the start was";
  EXPECT_NEAR(widened(1, 1), 1.0 / (0.05 * 0.05 + 0.09), 1e-3) << "across: own variance plus the landings' 0.3 m";
  EXPECT_NEAR(widened(5, 5), 0.0, 1e-12);
  EXPECT_NEAR(widened(2, 2), own(2, 2), 1e-9) << "depth as registered";
  EXPECT_NEAR(spread(0, 0), d * d, 1e-9);

  // Coming back in neither direction (a flat): nothing horizontal; a lost start: the same.
  others.landings = {{d, d}, {-d, d}};
  const Information6 flat = widened_by_doubt(own, others, spread);
  for (int k : {0, 1, 5}) EXPECT_NEAR(flat(k, k), 0.0, 1e-9) << k;
  others.landings = {{0.1, 0.1}, {-0.1, 0.1}};
  others.lost = true;
  const Information6 lost = widened_by_doubt(own, others, spread);
  for (int k : {0, 1, 5}) EXPECT_NEAR(lost(k, k), 0.0, 1e-9) << k;
}

TEST(DoubtWidens, AddsTheSpreadToTheAnswersOwnCovarianceEvenWhereItObservesOneDirectionOnly) {
  Information6 own = information_from_sigmas({0.1, 0.1, 0.05}, {0.002, 0.002, 0.004});
  Eigen::Matrix2d spread = Eigen::Vector2d(4.0, 0.25).asDiagonal();
  Information6 widened = with_horizontal_spread(own, spread);
  EXPECT_NEAR(widened(0, 0), 1.0 / (0.01 + 4.0), 1e-3);
  EXPECT_NEAR(widened(1, 1), 1.0 / (0.01 + 0.25), 1e-3);
  EXPECT_NEAR(widened(0, 1), 0.0, 1e-12);

  // Observed across only (y): along stays unobserved whatever the spread.
  own = without_direction(own, Eigen::Vector2d(1, 0));
  EXPECT_NEAR(own(0, 0), 0.0, 1e-12);
  EXPECT_NEAR(own(1, 1), 100.0, 1e-9);
  widened = with_horizontal_spread(own, spread);
  EXPECT_NEAR(widened(0, 0), 0.0, 1e-6);
  EXPECT_NEAR(widened(1, 1), 1.0 / (0.01 + 0.25), 1e-3);

  // A direction at 45 degrees taken out of an isotropic block leaves the other diagonal.
  const Information6 diagonal = without_direction(information_from_sigmas({0.1, 0.1, 0.05}, {0.002, 0.002, 0.004}),
                                                  Eigen::Vector2d(1, 1));
  const Eigen::Vector2d across(1, -1);
  EXPECT_NEAR((diagonal.topLeftCorner<2, 2>() * Eigen::Vector2d(1, 1)).norm(), 0.0, 1e-9);
  EXPECT_NEAR(across.dot(diagonal.topLeftCorner<2, 2>() * across) / across.squaredNorm(), 100.0, 1e-9);
}

// Where the answer's own information is small in absolute terms (deep water: sigmas of a hundred
// metres) and the competitors lie on one line oblique to the axes, the widened information is
// still never more than the answer's own: at 1500 m the old form gave 8.8 per m² for 4e-5.
TEST(DoubtWidens, NeverClaimsMoreThanTheAnswerItselfAtAnyScale) {
  const double scale = 128;  // the footprint's, 1500 m against the lake's 10 m
  Information6 own = information_from_sigmas({0.1 * scale * 12, 0.1 * scale * 18, 0.05 * scale}, {0.002, 0.002, 0.004});
  own(0, 1) = own(1, 0) = -0.5 * std::sqrt(own(0, 0) * own(1, 1));
  for (double angle : {0.0, 0.3, 0.98, 1.3}) {
    const Eigen::Vector2d line(std::cos(angle), std::sin(angle));
    const Eigen::Matrix2d spread = 461.5 * 461.5 * line * line.transpose();  // competitors on one line
    const Information6 widened = with_horizontal_spread(own, spread);
    const Eigen::Matrix2d excess = own.topLeftCorner<2, 2>() - widened.topLeftCorner<2, 2>();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> kept(widened.topLeftCorner<2, 2>());
    EXPECT_GE(kept.eigenvalues().minCoeff(), -1e-12 * own(0, 0)) << angle;
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(excess).eigenvalues().minCoeff(), -1e-9 * own(0, 0)) << angle;
    // Across the line nothing was added: the answer's own variance there (the marginal's).
    const Eigen::Vector2d across(-line.y(), line.x());
    const Eigen::Matrix2d own_covariance = own.topLeftCorner<2, 2>().inverse();
    const Eigen::Matrix2d widened_covariance = own_covariance + spread;
    EXPECT_NEAR(across.dot(widened.topLeftCorner<2, 2>() * across), across.dot(widened_covariance.inverse() * across),
                1e-6 * own(0, 0))
        << angle;
  }
}

// The cost's valley oblique to the direction taken out (sand waves: GICP's valley runs along one
// train's crests at 113 degrees, the probe's competitors along another's at 68): an answer that
// slid 2 m down the valley must not pull the graph across the competitors' line. Projected out,
// the direction left kept half the steep side's curvature (the 2 m slide read as 10 sigma);
// marginalised, only what the valley itself observes.
TEST(DoubtWidens, ADirectionTakenOutIsMarginalisedSoThatASlideDownAnObliqueValleyCostsNothing) {
  const double valley = 113 * M_PI / 180, removed = 68 * M_PI / 180;
  const Eigen::Vector2d along(std::cos(valley), std::sin(valley)), steep(-along.y(), along.x());
  Information6 own = Information6::Zero();
  own.topLeftCorner<2, 2>() = 100.0 * steep * steep.transpose() + 0.01 * along * along.transpose();
  own(2, 2) = 400;
  const Information6 out = without_direction(own, Eigen::Vector2d(std::cos(removed), std::sin(removed)));

  Vector6 slid = Vector6::Zero();
  slid.head<2>() = 2.0 * along;
  EXPECT_LT(std::sqrt(slid.dot(out * slid)), 0.5) << "a slide down the valley, in sigmas";
  Vector6 across = Vector6::Zero();
  across.head<2>() = steep;
  EXPECT_GT(across.dot(out * across), 0.0) << "the valley's own curvature stays";
  EXPECT_NEAR(out(2, 2), 400.0, 1e-9) << "depth, uncoupled, as registered";
  EXPECT_NEAR((out.topLeftCorner<2, 2>() * Eigen::Vector2d(std::cos(removed), std::sin(removed))).norm(), 0.0, 1e-9);
}

// A registration across two lines whose probe found sand waves' aliases.
Constraint among_sand_wave_aliases(const Survey2Lines& s) {
  Constraint c = registration(s, 15, 24);
  c.uniqueness = probed_with(sand_wave_aliases());
  c.registered_information = c.information;
  return c;
}

// A registration judged under Table 1's noise is judged again under the survey's: the prior's
// verdicts are not final, a refusal (feature-aided answers refused among plausible aliases) as
// much as a loss of information.
TEST(AliasFromPrior, AVerdictIsTakenAgainUnderABetterNoiseModel) {
  const Survey2Lines s = two_lines(20, 7);
  Constraint c = among_sand_wave_aliases(s);
  PipelineConfig config;
  const Plan plan = plan_of(config);
  const DrNoiseModel table_1(s.result.dr_poses, GraphConfig{}), survey(s.result.dr_poses, survey_noise());

  config.quality.feature_aliases_as_direct = false;
  judge_with_prior(c, table_1, table_1, s.result.dr_poses, config, plan);
  ASSERT_EQ(c.rejection.kind, RejectionKind::kNotUnique);
  judge_with_prior(c, survey, survey, s.result.dr_poses, config, plan);
  EXPECT_TRUE(c.accepted()) << c.rejection.text();
  EXPECT_EQ(c.alias, AliasResolution::kRuledOut);

  config.quality.feature_aliases_as_direct = true;
  judge_with_prior(c, table_1, table_1, s.result.dr_poses, config, plan);
  ASSERT_EQ(c.alias, AliasResolution::kInformationRemoved);
  ASSERT_LT(c.information(0, 0), 0.1 * c.registered_information(0, 0));
  judge_with_prior(c, survey, survey, s.result.dr_poses, config, plan);
  EXPECT_TRUE(c.accepted()) << c.rejection.text();
  EXPECT_EQ(c.alias, AliasResolution::kRuledOut);
  EXPECT_EQ(c.information, c.registered_information) << "its own information back";
}

// The survey's estimate gives the DR gate a looser heading than the likeliest
// (navigation_noise.h); the aliases are judged under the model given for them, not the gate's.
TEST(AliasFromPrior, AliasesAreJudgedUnderTheirOwnModelNotTheGates) {
  const Survey2Lines s = two_lines(20, 7);
  Constraint c = among_sand_wave_aliases(s);
  const PipelineConfig config;
  const Plan plan = plan_of(config);
  const DrNoiseModel table_1(s.result.dr_poses, GraphConfig{}), survey(s.result.dr_poses, survey_noise());
  judge_with_prior(c, table_1, survey, s.result.dr_poses, config, plan);
  EXPECT_TRUE(c.accepted()) << c.rejection.text();
  EXPECT_EQ(c.alias, AliasResolution::kRuledOut);
  judge_with_prior(c, survey, table_1, s.result.dr_poses, config, plan);
  EXPECT_TRUE(c.accepted()) << c.rejection.text();
  EXPECT_EQ(c.alias, AliasResolution::kInformationRemoved);
}

// Where dead reckoning allows a sand-wave alias (Table 1's noise), the graph kept before may not
// (robustness.alias_from_graph): with the pair placed to a metre, the aliases 10 m away are ruled
// out and the answer keeps its information, as well as the probe's step (1 m) places it, also when
// judged again under dead reckoning alone. An answer the graph itself does not allow (5 m from
// where it puts the pair, its aliases 5 and 15 m from there) gets nothing from it.
TEST(AliasFromGraph, AnAliasTheGraphRulesOutStaysRuledOutWhenDeadReckoningAloneWouldAllowIt) {
  const Survey2Lines s = two_lines(20, 7);
  PipelineConfig config;
  config.robustness.alias_from_graph = true;
  const Plan plan = plan_of(config);
  ASSERT_TRUE(plan.alias_from_graph);
  const DrNoiseModel table_1(s.result.dr_poses, GraphConfig{});
  // The graph's estimate is the truth, its covariance of the pair a metre each way.
  const Eigen::Matrix2d metre = Eigen::Matrix2d::Identity();

  Constraint c = direct_registration(s, 15, 24, probed_with(sand_wave_aliases()));
  c.registered_information = c.information;
  judge_with_prior(c, table_1, table_1, s.result.dr_poses, config, plan);
  ASSERT_EQ(c.alias, AliasResolution::kInformationRemoved) << "dead reckoning alone allows the aliases";
  ASSERT_LT(c.information(0, 0), 0.01 * c.registered_information(0, 0)) << "nothing across the crests";

  const AliasGate graph = graph_alias_gate(c, s.truth, metre);
  judge_with_prior(c, table_1, table_1, s.result.dr_poses, config, plan, &graph);
  ASSERT_TRUE(c.accepted()) << c.rejection.text();
  EXPECT_EQ(c.alias, AliasResolution::kJudgedByGraph);
  // Every alias ruled out: its own 0.1 m sigmas, widened by the probe's 1 m step.
  const double widened = 1 / (1 / c.registered_information(0, 0) + 1.0);
  EXPECT_NEAR(c.information(0, 0), widened, 1e-6);
  EXPECT_NEAR(c.information(1, 1), widened, 1e-6);
  EXPECT_GT(c.information(2, 2), 50.0) << "depth as registered";
  const Information6 judged = c.information;
  judge_with_prior(c, table_1, table_1, s.result.dr_poses, config, plan);
  EXPECT_EQ(c.alias, AliasResolution::kJudgedByGraph) << "the graph's verdict stands under a new DR model";
  EXPECT_EQ(c.information, judged);

  // GICP slid 5 m from where the graph puts the pair: the graph does not vouch for it, though it
  // would rule out every alias of it.
  Constraint slid = direct_registration(s, 15, 24, probed_with(sand_wave_aliases()));
  slid.measured = pose(5, 0, 0) * slid.measured;
  slid.registered_information = slid.information;
  const AliasGate slid_graph = graph_alias_gate(slid, s.truth, metre);
  judge_with_prior(slid, table_1, table_1, s.result.dr_poses, config, plan, &slid_graph);
  EXPECT_EQ(slid.alias, AliasResolution::kInformationRemoved);
  EXPECT_LT(slid.information(0, 0), 0.01 * slid.registered_information(0, 0));
  EXPECT_FALSE(slid.graph_information.has_value());
}

}  // namespace
}  // namespace bathyslam
