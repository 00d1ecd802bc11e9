// The robust back end: DR noise and plausibility, pairwise loop consistency, the DCS kernel,
// the per-line check, and all of them against a lawnmower with wrong loop closures.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <algorithm>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

#include "core/graph/dr_noise.h"
#include "core/graph/graph_check.h"
#include "core/graph/loop_consistency.h"
#include "core/graph/pose_graph.h"
#include "core/graph/robust_kernel.h"

namespace bathyslam {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Isometry3d pose(double x, double y, double yaw, double z = -10.0) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = Eigen::Vector3d(x, y, z);
  p.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return p;
}

// `pose` perturbed as the parametrisation says: turned by δθ, moved by δt, both in the frame
// the pose is expressed in.
Eigen::Isometry3d perturbed(const Eigen::Isometry3d& p, const Vector6& delta) {
  Eigen::Isometry3d q = p;
  const Eigen::Vector3d angle = delta.tail<3>();
  if (angle.norm() > 0) q.linear() = Eigen::AngleAxisd(angle.norm(), angle.normalized()) * p.linear();
  q.translation() += delta.head<3>();
  return q;
}

// A straight run east, then a turn and back west 30 m north: 2·n nodes, 20 m apart.
std::vector<Eigen::Isometry3d> out_and_back(int n) {
  std::vector<Eigen::Isometry3d> dr;
  for (int i = 0; i < n; ++i) dr.push_back(pose(20.0 * i, 0, 0));
  for (int i = n - 1; i >= 0; --i) dr.push_back(pose(20.0 * i, 30.0, M_PI));
  return dr;
}

// DR re-run with every step perturbed by GraphConfig's DR noise, in the step's level frame.
std::vector<Eigen::Isometry3d> noisy_chain(const std::vector<Eigen::Isometry3d>& dr, const GraphConfig& config,
                                           std::mt19937& rng) {
  std::normal_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::Isometry3d> chain = {dr[0]};
  for (std::size_t m = 1; m < dr.size(); ++m) {
    Vector6 noise;
    for (int k = 0; k < 3; ++k) noise(k) = config.dr_sigma_translation_m(k) * unit(rng);
    for (int k = 0; k < 3; ++k) noise(3 + k) = config.dr_sigma_rotation_rad(k) * unit(rng);
    chain.push_back(chain.back() * perturbed(dr[m - 1].inverse() * dr[m], noise));
  }
  return chain;
}

Information6 registration_information() { return information_from_sigmas({0.3, 0.3, 0.2}, {0.2 * kDeg, 0.2 * kDeg, 0.3 * kDeg}); }

// ---- DR noise -------------------------------------------------------------------------------

// Whitened by the model, the sample covariance of each pair's relative pose over 20,000 chains
// drawn by `sample` (DR re-run with sampled noise) is ≈ I.
void expect_monte_carlo_matches(const DrNoiseModel& model, const std::vector<std::pair<int, int>>& pairs,
                                const std::function<std::vector<Eigen::Isometry3d>()>& sample) {
  std::vector<std::vector<Vector6>> errors(pairs.size());
  for (int n = 0; n < 20000; ++n) {
    const std::vector<Eigen::Isometry3d> chain = sample();
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const auto [from, to] = pairs[k];
      errors[k].push_back(pose_difference(chain[from].inverse() * chain[to], model.relative_pose(from, to)));
    }
  }
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    Covariance6 covariance = Covariance6::Zero();
    for (const Vector6& e : errors[k]) covariance += e * e.transpose() / errors[k].size();
    const Eigen::LLT<Covariance6> llt(model.covariance(pairs[k].first, pairs[k].second));
    const Covariance6 inverse_root = llt.matrixL().solve(Covariance6::Identity());
    const Eigen::SelfAdjointEigenSolver<Covariance6> whitened(inverse_root * covariance * inverse_root.transpose());
    EXPECT_GT(whitened.eigenvalues().minCoeff(), 0.93) << pairs[k].first << "->" << pairs[k].second;
    EXPECT_LT(whitened.eigenvalues().maxCoeff(), 1.07) << pairs[k].first << "->" << pairs[k].second;
  }
}

// The first-order covariance against the spread of DR re-run with sampled step noise, both ways
// along the chain and across the turn.
TEST(DrNoise, CovarianceMatchesMonteCarloOfNoisyChains) {
  const std::vector<Eigen::Isometry3d> dr = out_and_back(15);
  const GraphConfig config;
  std::mt19937 rng(11);
  expect_monte_carlo_matches(DrNoiseModel(dr, config), {{0, 12}, {3, 25}, {25, 3}, {29, 14}, {7, 8}},
                             [&] { return noisy_chain(dr, config, rng); });
}

// Two surveys of one site: the second's chain hangs off node 0 by its datum edge (both start
// fixes), so nodes of the two surveys are joined through their starts, never through the end of
// the first survey's chain. Against Monte Carlo as above.
TEST(DrNoise, SecondSurveyHangsOffTheDatumByItsStartFixes) {
  std::vector<Eigen::Isometry3d> dr = out_and_back(8);  // nodes 0-15
  for (int i = 0; i < 10; ++i) dr.push_back(pose(10.0 + 20.0 * i * std::cos(0.3), 15.0 + 20.0 * i * std::sin(0.3), 0.3));
  GraphConfig config;
  config.dr_sigma_translation_m = {0.5, 0.5, 0.1};
  config.dr_sigma_rotation_rad = {1e-4, 1e-4, 5e-3};
  config.survey_starts = {16};
  const DrNoiseModel model(dr, config);
  const std::vector<Eigen::Isometry3d> first(dr.begin(), dr.begin() + 16), second(dr.begin() + 16, dr.end());
  std::mt19937 rng(5);
  std::normal_distribution<double> unit(0.0, 1.0);
  expect_monte_carlo_matches(model, {{3, 20}, {20, 3}, {15, 25}, {17, 24}, {0, 16}}, [&] {
    std::vector<Eigen::Isometry3d> chain = noisy_chain(first, config, rng);
    Vector6 fix;
    for (int k = 0; k < 3; ++k) fix(k) = std::sqrt(2.0) * config.start_sigma_translation_m(k) * unit(rng);
    for (int k = 0; k < 3; ++k) fix(3 + k) = std::sqrt(2.0) * config.start_sigma_rotation_rad(k) * unit(rng);
    const Eigen::Isometry3d start = chain[0] * perturbed(dr[0].inverse() * dr[16], fix);
    for (const Eigen::Isometry3d& p : noisy_chain(second, config, rng)) chain.push_back(start * second[0].inverse() * p);
    return chain;
  });
  // Within the second survey, as a chain of its own: no trace of the first survey's drift.
  const DrNoiseModel alone(std::vector<Eigen::Isometry3d>(dr.begin() + 16, dr.end()), GraphConfig{config.dr_sigma_translation_m,
                                                                                                   config.dr_sigma_rotation_rad});
  EXPECT_TRUE(model.covariance(17, 24).isApprox(alone.covariance(1, 8), 1e-9));
}

TEST(DrNoise, OneStepIsTheStepNoiseAndNoStepIsNone) {
  const std::vector<Eigen::Isometry3d> dr = out_and_back(5);
  const GraphConfig config;
  const DrNoiseModel model(dr, config);
  Vector6 variances;
  variances << config.dr_sigma_translation_m.cwiseAbs2(), config.dr_sigma_rotation_rad.cwiseAbs2();
  // Step 6 -> 7 heads west; in its own level frame the noise is the configured one.
  EXPECT_TRUE(model.covariance(6, 7).isApprox(Covariance6(variances.asDiagonal()), 1e-9));
  EXPECT_TRUE(model.covariance(4, 4).isZero(1e-12));
  EXPECT_TRUE(dr_relative_covariance(dr, 2, 8, config).isApprox(model.covariance(2, 8), 1e-12));
}

TEST(DrNoise, LevelFramesDropRollAndPitchOnly) {
  Eigen::Isometry3d tilted = pose(5, 6, 0.7);
  tilted.linear() = tilted.linear() * Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Isometry3d level = level_frame(tilted);
  EXPECT_TRUE(level.translation().isApprox(tilted.translation()));
  EXPECT_TRUE(level.linear().isApprox(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix()));
  const Eigen::Isometry3d other = pose(25, 6, 0.9);
  EXPECT_TRUE(between_level_frames(tilted.inverse() * other, tilted, other).isApprox(level.inverse() * other));
}

// ---- plausibility ---------------------------------------------------------------------------

TEST(Plausibility, YawIsWrappedSo180DegreesIsTheWorst) {
  const Covariance6 covariance = Covariance6::Identity();
  const Eigen::Isometry3d predicted = pose(20, 0, 0.1);
  auto yaw_distance = [&](double turn) {
    return std::sqrt(plausibility(predicted * pose(0, 0, turn, 0), predicted, covariance).mahalanobis2);
  };
  EXPECT_NEAR(yaw_distance(180 * kDeg), M_PI, 1e-6);
  EXPECT_NEAR(yaw_distance(200 * kDeg), 160 * kDeg, 1e-6);
  EXPECT_NEAR(yaw_distance(-170 * kDeg), 170 * kDeg, 1e-6);
  EXPECT_NEAR(yaw_distance(359 * kDeg), 1 * kDeg, 1e-6);
}

TEST(Plausibility, A120DegreeTurnAcross20MinutesIsImplausible) {
  std::vector<Eigen::Isometry3d> dr;
  for (int i = 0; i <= 120; ++i) dr.push_back(pose(20.0 * i, 0, 0));  // 120 steps of 10 s
  const DrNoiseModel model(dr, GraphConfig{});
  const Eigen::Isometry3d predicted = model.relative_pose(0, 120);
  const Covariance6 covariance =
      model.covariance(0, 120) + measurement_covariance({0, 120, predicted, registration_information(), true}, dr[0]);
  const PlausibilityTest turned = plausibility(predicted * pose(0, 0, 120 * kDeg, 0), predicted, covariance);
  EXPECT_FALSE(turned.plausible) << turned.mahalanobis2;
  EXPECT_EQ(turned.dof, 3);
  EXPECT_TRUE(plausibility(predicted, predicted, covariance).plausible);
}

// A measurement that is DR re-run with the model's own step noise passes at the test's level,
// and its squared distance averages χ²₃'s mean, 3 (a covariance too large would pass too).
TEST(Plausibility, DrWithModelNoiseIsPlausibleAtTheTestLevel) {
  const std::vector<Eigen::Isometry3d> dr = out_and_back(30);
  const GraphConfig config;
  const DrNoiseModel model(dr, config);
  const int from = 5, to = 50;
  const Covariance6 covariance = model.covariance(from, to);
  std::mt19937 rng(3);
  int plausible = 0;
  double sum = 0;
  const int draws = 2000;
  for (int k = 0; k < draws; ++k) {
    const std::vector<Eigen::Isometry3d> chain = noisy_chain(dr, config, rng);
    const PlausibilityTest test = plausibility(chain[from].inverse() * chain[to], model.relative_pose(from, to), covariance);
    plausible += test.plausible;
    sum += test.mahalanobis2;
  }
  EXPECT_GT(plausible, 0.99 * draws);
  EXPECT_NEAR(sum / draws, 3.0, 0.25);
}

// Across 100 steps (2 km) yaw noise alone lets the end wander tens of metres slightly_turned; across
// one step only the step's 5 m. The same slightly_turned offset passes the first and not the second.
TEST(Plausibility, ALateralOffsetIsJudgedByTheChainItCrosses) {
  std::vector<Eigen::Isometry3d> dr;
  for (int i = 0; i <= 100; ++i) dr.push_back(pose(20.0 * i, 0, 0));
  const GraphConfig config;
  const DrNoiseModel model(dr, config);
  const double offset = 2000.0 * config.dr_sigma_rotation_rad.z() * 2.0;  // d·σ_yaw·2 = 40 m
  auto test = [&](int from, int to) {
    const Eigen::Isometry3d predicted = model.relative_pose(from, to);
    const Eigen::Isometry3d measured = pose(0, offset, 0, 0) * predicted;
    const Covariance6 covariance = model.covariance(from, to) +
                                   measurement_covariance({from, to, measured, registration_information(), true}, dr[from]);
    return plausibility(measured, predicted, covariance);
  };
  EXPECT_TRUE(test(0, 100).plausible) << test(0, 100).mahalanobis2;
  EXPECT_FALSE(test(50, 51).plausible) << test(50, 51).mahalanobis2;
}

// A registration that pins the overlap 30 m to the side but its yaw only loosely: at `to`'s
// origin its uncertainty slightly_turned is the lever arm times the yaw's.
TEST(Plausibility, AMeasurementsCovarianceMovesFromItsAnchorToTheOrigin) {
  const Information6 information = information_from_sigmas({0.1, 0.1, 0.1}, {0.01, 0.01, 0.05});
  const PoseGraphEdge edge{0, 1, pose(0, 30, 0, 0), information, true, Eigen::Vector3d(0, -15, 10)};
  const Covariance6 covariance = measurement_covariance(edge, pose(0, 0, 0));
  EXPECT_NEAR(covariance(0, 0), 0.1 * 0.1 + 15.0 * 15.0 * 0.05 * 0.05 + 10.0 * 10.0 * 0.01 * 0.01, 1e-9)
      << "x moves with yaw at 15 m and with pitch at 10 m";
  EXPECT_NEAR(covariance(1, 1), 0.1 * 0.1 + 10.0 * 10.0 * 0.01 * 0.01, 1e-9) << "y moves with roll at 10 m";
  EXPECT_NEAR(covariance(5, 5), 0.05 * 0.05, 1e-12);

  Information6 flat = information;
  flat(0, 0) = flat(1, 1) = 0;
  EXPECT_NEAR(measurement_covariance({0, 1, pose(0, 30, 0, 0), flat, true}, pose(0, 0, 0))(0, 0), 1e4, 1e-6)
      << "unobserved directions get the large variance";
}

// ---- DCS ------------------------------------------------------------------------------------

TEST(DcsLoss, DerivativesAreConsistentAndTheWeightIsTheSquaredScale) {
  const double phi = 2.5;
  const DcsLoss loss(phi);
  auto rho = [&](double s) {
    double r[3];
    loss.Evaluate(s, r);
    return std::array<double, 3>{r[0], r[1], r[2]};
  };
  for (double s : {0.1, 1.0, 2.4, 2.6, 5.0, 40.0, 1e4}) {
    const double h = 1e-5 * std::max(1.0, s);
    const auto r = rho(s);
    EXPECT_NEAR(r[1], (rho(s + h)[0] - rho(s - h)[0]) / (2 * h), 1e-6) << s;
    EXPECT_NEAR(r[2], (rho(s + h)[1] - rho(s - h)[1]) / (2 * h), 1e-6) << s;
    const double scale = std::min(1.0, 2 * phi / (phi + s));
    EXPECT_NEAR(r[1], scale * scale, 1e-12) << s;
  }
  EXPECT_NEAR(rho(phi)[0], phi, 1e-12);
  EXPECT_NEAR(rho(phi * (1 + 1e-12))[0], phi, 1e-9) << "continuous at Φ";
  EXPECT_LT(rho(1e12)[0], 3 * phi) << "a wrong edge costs at most 3Φ";
}

// One wrong edge against three that agree: Huber still lets it pull a few centimetres, DCS
// almost nothing.
TEST(DcsLoss, AWrongEdgePullsLessUnderDcsThanUnderHuber) {
  const std::vector<Eigen::Isometry3d> truth = {pose(0, 0, 0), pose(20, 0, 0)};
  const Eigen::Isometry3d relative = truth[0].inverse() * truth[1];
  const Information6 info = information_from_sigmas({0.1, 0.1, 0.1}, {0.01, 0.01, 0.01});
  std::vector<PoseGraphEdge> edges = {{0, 1, relative, information_from_sigmas({5, 5, 1}, {1e-4, 1e-4, 1e-2}), false}};
  for (int k = 0; k < 3; ++k) edges.push_back({0, 1, relative, info, true});
  edges.push_back({0, 1, pose(0, 10, 0, 0) * relative, info, true});
  auto error = [&](RobustKernel kernel) {
    GraphConfig config;
    config.robust_kernel = kernel;
    const GraphSolution solution = optimize_pose_graph({truth[0], truth[1] * pose(1, 1, 0.01, 0)}, edges, config);
    EXPECT_TRUE(solution.converged);
    return (solution.poses[1].translation() - truth[1].translation()).norm();
  };
  EXPECT_EQ(GraphConfig{}.robust_kernel, RobustKernel::huber) << "Huber stays the default";
  const double huber = error(RobustKernel::huber), dcs = error(RobustKernel::dcs);
  EXPECT_GT(huber, 0.01);
  EXPECT_LT(dcs, 0.1 * huber);
}

// ---- the lawnmower ---------------------------------------------------------------------------

// Six lines of 30 nodes, 20 m apart along the line and 30 m between lines, one turn node
// between lines, a transit and a check line crossing them all. DR drifts in heading.
struct Survey {
  std::vector<Eigen::Isometry3d> truth, dr;
  std::vector<int> line;  // per node; −1 turn or transit
  std::vector<PoseGraphEdge> odometry;
};

Survey lawnmower(unsigned seed) {
  Survey s;
  auto add = [&](double x, double y, double yaw, int line) {
    s.truth.push_back(pose(x, y, yaw));
    s.line.push_back(line);
  };
  for (int l = 0; l < 6; ++l) {
    const bool east = l % 2 == 0;
    for (int i = 0; i < 30; ++i) add(east ? 20.0 * i : 580.0 - 20.0 * i, 30.0 * l, east ? 0 : M_PI, l);
    if (l < 5) add(east ? 600.0 : -20.0, 30.0 * l + 15, M_PI / 2, -1);
  }
  for (int i = 0; i < 14; ++i) add(20.0 + 20.0 * i, 170.0, 0, -1);
  for (int i = 0; i < 10; ++i) add(290.0, 170.0 - 20.0 * i, -M_PI / 2, 6);

  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  s.dr = {s.truth[0]};
  for (std::size_t i = 1; i < s.truth.size(); ++i) {
    Vector6 noise;
    noise << 0.3 * unit(rng), 0.3 * unit(rng), 0.05 * unit(rng), 1e-4 * unit(rng), 1e-4 * unit(rng),
        0.001 + 0.002 * unit(rng);  // a gyro bias of 0.06° a step and its noise
    s.dr.push_back(s.dr.back() * perturbed(s.truth[i - 1].inverse() * s.truth[i], noise));
  }
  const GraphConfig config;
  s.odometry = odometry_edges(s.dr, information_from_sigmas(config.dr_sigma_translation_m, config.dr_sigma_rotation_rad));
  return s;
}

int nearest_on_line(const Survey& s, int node, int line) {
  int best = -1;
  for (int j = 0; j < static_cast<int>(s.truth.size()); ++j) {
    if (s.line[j] != line) continue;
    const double d = (s.truth[j].translation() - s.truth[node].translation()).head<2>().norm();
    if (best < 0 || d < (s.truth[best].translation() - s.truth[node].translation()).head<2>().norm()) best = j;
  }
  return best;
}

// A registration at the truth with noise drawn from its own information.
PoseGraphEdge registration(const Survey& s, int a, int b, std::mt19937& rng) {
  std::normal_distribution<double> unit(0.0, 1.0);
  Vector6 noise;
  noise << 0.3 * unit(rng), 0.3 * unit(rng), 0.2 * unit(rng), 0.2 * kDeg * unit(rng), 0.2 * kDeg * unit(rng),
      0.3 * kDeg * unit(rng);
  const int from = std::min(a, b), to = std::max(a, b);
  return {from, to, perturbed(s.truth[from].inverse() * s.truth[to], noise), registration_information(), true};
}

// Adjacent-line edges every third node; loops from the check line to every line and between
// every other line every sixth node.
struct Registrations {
  std::vector<PoseGraphEdge> adjacent, loops;
};

Registrations registrations(const Survey& s, std::mt19937& rng) {
  Registrations r;
  std::vector<PoseGraphEdge>& adjacent = r.adjacent;
  std::vector<PoseGraphEdge>& loops = r.loops;
  for (int i = 0; i < static_cast<int>(s.truth.size()); ++i) {
    const int l = s.line[i];
    if (l < 0 || l > 5) continue;
    const int within = i - l * 31;  // 30 nodes and a turn per line
    if (l < 5 && within % 3 == 0) adjacent.push_back(registration(s, i, nearest_on_line(s, i, l + 1), rng));
    if (l < 4 && within % 6 == 1) loops.push_back(registration(s, i, nearest_on_line(s, i, l + 2), rng));
  }
  for (int i = 0; i < static_cast<int>(s.truth.size()); ++i) {
    if (s.line[i] != 6) continue;
    for (int l = 0; l < 6; ++l) {
      const int j = nearest_on_line(s, i, l);
      if ((s.truth[j].translation() - s.truth[i].translation()).head<2>().norm() < 12.0) {
        loops.push_back(registration(s, i, j, rng));
      }
    }
  }
  return r;
}

// A loop gone wrong: its measurement moved up to 50 m and turned up to 180°, at random.
PoseGraphEdge wrong(PoseGraphEdge edge, std::mt19937& rng) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double distance = 50.0 * uniform(rng), direction = 2 * M_PI * uniform(rng);
  const double turn = M_PI * (2 * uniform(rng) - 1);
  edge.measured = edge.measured * pose(distance * std::cos(direction), distance * std::sin(direction), turn, 0);
  return edge;
}

std::vector<PoseGraphEdge> joined(std::vector<PoseGraphEdge> a, const std::vector<PoseGraphEdge>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

double max_error(const std::vector<Eigen::Isometry3d>& poses, const std::vector<Eigen::Isometry3d>& truth) {
  double e = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) e = std::max(e, (poses[i].translation() - truth[i].translation()).norm());
  return e;
}

double rms_error(const std::vector<Eigen::Isometry3d>& poses, const std::vector<Eigen::Isometry3d>& truth) {
  double sum = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) sum += (poses[i].translation() - truth[i].translation()).squaredNorm();
  return std::sqrt(sum / poses.size());
}

std::vector<LoopCandidate> candidates_of(const std::vector<PoseGraphEdge>& edges, const std::vector<Eigen::Isometry3d>& dr) {
  std::vector<LoopCandidate> candidates;
  for (const PoseGraphEdge& e : edges) candidates.push_back(loop_candidate(e, dr));
  return candidates;
}

// ---- loop consistency -----------------------------------------------------------------------

TEST(MaximumClique, BranchAndBoundMatchesExhaustiveSearch) {
  std::mt19937 rng(7);
  std::bernoulli_distribution edge(0.5);
  for (int trial = 0; trial < 30; ++trial) {
    const int n = 14;
    Adjacency adjacency(n, std::vector<char>(n, 0));
    for (int a = 0; a < n; ++a) {
      for (int b = a + 1; b < n; ++b) adjacency[a][b] = adjacency[b][a] = edge(rng);
    }
    int largest = 0;
    for (int subset = 1; subset < (1 << n); ++subset) {
      bool clique = true;
      for (int a = 0; a < n && clique; ++a) {
        for (int b = a + 1; b < n && clique; ++b) {
          if ((subset >> a & 1) && (subset >> b & 1) && !adjacency[a][b]) clique = false;
        }
      }
      if (clique) largest = std::max(largest, __builtin_popcount(subset));
    }
    const Clique exact = maximum_clique(adjacency);
    EXPECT_TRUE(exact.exact);
    EXPECT_EQ(static_cast<int>(exact.members.size()), largest) << "trial " << trial;
    for (int a : exact.members) {
      for (int b : exact.members) EXPECT_TRUE(a == b || adjacency[a][b]);
    }
    const Clique greedy = maximum_clique(adjacency, 0);
    EXPECT_FALSE(greedy.exact);
    EXPECT_LE(greedy.members.size(), exact.members.size());
    for (int a : greedy.members) {
      for (int b : greedy.members) EXPECT_TRUE(a == b || adjacency[a][b]);
    }
  }
}

// The greedy search as maximum_clique documents it, written plainly: from each vertex, repeatedly
// add the candidate of highest degree (the first such) adjacent to every member so far; the
// largest found, the first of equal size.
std::vector<int> plain_greedy_clique(const Adjacency& adjacency) {
  const int n = static_cast<int>(adjacency.size());
  std::vector<int> degree(n, 0), best;
  for (int v = 0; v < n; ++v) degree[v] = static_cast<int>(std::count(adjacency[v].begin(), adjacency[v].end(), 1));
  for (int seed = 0; seed < n; ++seed) {
    std::vector<int> clique = {seed}, fitting;  // fitting: adjacent to every member
    for (int v = 0; v < n; ++v) {
      if (adjacency[seed][v]) fitting.push_back(v);
    }
    while (!fitting.empty()) {
      int next = fitting[0];
      for (int v : fitting) next = degree[v] > degree[next] ? v : next;
      clique.push_back(next);
      std::erase_if(fitting, [&](int v) { return !adjacency[next][v]; });
    }
    if (clique.size() > best.size()) best = clique;
  }
  std::sort(best.begin(), best.end());
  return best;
}

TEST(MaximumClique, TheGreedySearchOnManyLoopsIsTheDocumentedOne) {
  std::mt19937 rng(11);
  for (const double density : {0.3, 0.9, 0.99}) {
    std::bernoulli_distribution edge(density);
    const int n = 300;  // several words of bits, above the exact search's default size
    Adjacency adjacency(n, std::vector<char>(n, 0));
    for (int a = 0; a < n; ++a) {
      for (int b = a + 1; b < n; ++b) adjacency[a][b] = adjacency[b][a] = edge(rng);
    }
    const Clique greedy = maximum_clique(adjacency, 0);
    EXPECT_EQ(greedy.members, plain_greedy_clique(adjacency)) << "density " << density;
  }
}

// Two vertices the missing edges do not join are always adjacent, so the largest clique is the
// largest of each group the missing edges join, put together: as large as the search over the
// whole graph finds, and exact on thousands of loops that disagree in small groups.
TEST(MaximumClique, GroupsOfMissingEdgesGiveTheWholeGraphsLargestClique) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 40;
    std::uniform_int_distribution<int> vertex(0, n - 1);
    std::vector<std::pair<int, int>> missing;
    Adjacency adjacency(n, std::vector<char>(n, 1));
    for (int v = 0; v < n; ++v) adjacency[v][v] = 0;
    for (int k = 0; k < 3 * trial; ++k) {
      const int a = vertex(rng), b = vertex(rng);
      if (a == b || !adjacency[a][b]) continue;
      adjacency[a][b] = adjacency[b][a] = 0;
      missing.emplace_back(std::min(a, b), std::max(a, b));
    }
    const Clique whole = maximum_clique(adjacency);
    const Clique grouped = maximum_clique_missing(n, missing);
    ASSERT_TRUE(whole.exact && grouped.exact);
    EXPECT_EQ(grouped.members.size(), whole.members.size()) << "trial " << trial;
    for (int a : grouped.members) {
      for (int b : grouped.members) EXPECT_TRUE(a == b || adjacency[a][b]) << "trial " << trial;
    }
  }
  // 3,000 loops, 100 pairs of which disagree: one of each pair goes, every other loop stays.
  std::vector<std::pair<int, int>> pairs;
  for (int k = 0; k < 100; ++k) pairs.emplace_back(30 * k, 30 * k + 7);
  const Clique many = maximum_clique_missing(3000, pairs);
  EXPECT_TRUE(many.exact);
  EXPECT_EQ(many.members.size(), 2900u);
  // A group above the exact search's size is searched greedily, and the answer says so.
  std::vector<std::pair<int, int>> chain;
  for (int v = 0; v < 10; ++v) chain.emplace_back(v, v + 1);
  EXPECT_TRUE(maximum_clique_missing(20, chain, 11).exact);
  EXPECT_FALSE(maximum_clique_missing(20, chain, 10).exact);
}

TEST(LoopConsistency, ReversingALoopKeepsItsPairDistances) {
  const Survey s = lawnmower(1);
  std::mt19937 rng(2);
  const auto [adjacent, loops] = registrations(s, rng);
  const DrNoiseModel dr(s.dr, GraphConfig{});
  const LoopCandidate a = loop_candidate(loops[0], s.dr), b = loop_candidate(loops[5], s.dr);
  const LoopCandidate twice = reversed(reversed(a));
  EXPECT_TRUE(twice.measured.isApprox(a.measured, 1e-12));
  EXPECT_TRUE(twice.covariance.isApprox(a.covariance, 1e-9));
  const double forward = pair_mahalanobis2(a, b, dr);
  EXPECT_LT(forward, 16.27) << "two correct loops agree";
  // The same cycle walked the other way round: the same distance, to first order.
  EXPECT_NEAR(pair_mahalanobis2(b, a, dr), forward, 0.05 * forward + 0.05);
  PoseGraphEdge turned = loops[0];
  turned.measured = turned.measured * pose(0, 0, 90 * kDeg, 0);
  EXPECT_GT(pair_mahalanobis2(loop_candidate(turned, s.dr), b, dr), 16.27) << "with a wrong one";
}

// A loop turned 10° across a chain long enough for DR to allow it, but which its neighbours
// contradict: plausible, inconsistent. A 180° loop: implausible. The correct ones: kept.
TEST(LoopConsistency, KeepsTheAgreeingLoopsAndSaysWhyOthersGo) {
  const Survey s = lawnmower(3);
  std::mt19937 rng(4);
  const auto [adjacent, loops] = registrations(s, rng);
  std::vector<PoseGraphEdge> edges = joined(adjacent, loops);
  const int slightly_turned = 0, turned = static_cast<int>(edges.size()) - 1;
  ASSERT_GT(edges[slightly_turned].to - edges[slightly_turned].from, 50);  // a line's length and more
  edges[slightly_turned].measured = edges[slightly_turned].measured * pose(0, 0, 10 * kDeg, 0);
  edges[turned].measured = edges[turned].measured * pose(0, 0, M_PI, 0);
  const DrNoiseModel dr(s.dr, GraphConfig{});
  const LoopSelection selection = select_consistent_loops(candidates_of(edges, s.dr), dr);
  EXPECT_EQ(selection.verdicts[slightly_turned], LoopVerdict::inconsistent) << selection.dr_mahalanobis2[slightly_turned];
  EXPECT_EQ(selection.verdicts[turned], LoopVerdict::implausible);
  EXPECT_TRUE(selection.exact);
  EXPECT_GE(selection.kept.size(), edges.size() - 4) << "at most two correct loops lost";
}

TEST(LoopConsistency, ALonePlausibleLoopIsKeptTwoThatDisagreeAreNot) {
  const Survey s = lawnmower(5);
  std::mt19937 rng(6);
  const auto [adjacent, loops] = registrations(s, rng);
  const DrNoiseModel dr(s.dr, GraphConfig{});
  PoseGraphEdge good = adjacent[3], bad = adjacent[3];
  bad.measured = bad.measured * pose(0, 0, M_PI, 0);
  EXPECT_EQ(select_consistent_loops(candidates_of({good}, s.dr), dr).kept, std::vector<int>{0});
  EXPECT_EQ(select_consistent_loops(candidates_of({bad}, s.dr), dr).verdicts[0], LoopVerdict::implausible);
  PoseGraphEdge other = good;
  other.measured = pose(0, 12, 0, 0) * other.measured;  // within one step's DR noise, not the first's
  const LoopSelection pair = select_consistent_loops(candidates_of({good, other}, s.dr), dr);
  EXPECT_TRUE(pair.kept.empty());
  EXPECT_EQ(pair.verdicts[0], LoopVerdict::inconsistent);
  EXPECT_EQ(pair.verdicts[1], LoopVerdict::inconsistent);
}

// ---- graph check ----------------------------------------------------------------------------

TEST(ChiSquare, QuantilesMatchKnownValues) {
  EXPECT_NEAR(normal_quantile(0.975), 1.959963985, 1e-8);
  EXPECT_NEAR(normal_quantile(0.999), 3.090232306, 1e-8);
  EXPECT_NEAR(normal_quantile(0.01), -2.326347874, 1e-8);
  EXPECT_NEAR(normal_quantile(1e-6), -4.753424309, 1e-7);
  EXPECT_NEAR(chi_square_quantile(0.999, 3), 16.2662, 0.02 * 16.2662);
  EXPECT_NEAR(chi_square_quantile(0.999, 6), 22.4577, 0.01 * 22.4577);
  EXPECT_NEAR(chi_square_quantile(0.95, 30), 43.7730, 0.002 * 43.7730);
  EXPECT_NEAR(chi_square_quantile(0.999, 90), 137.2084, 0.003 * 137.2084);
  EXPECT_NEAR(chi_square_quantile(0.999, 300), 381.4252, 0.001 * 381.4252);
}

TEST(LineRuns, RunsAreConsecutiveNodesOfOneLine) {
  const std::vector<LineRun> runs = line_runs({-1, 0, 0, 0, -1, 1, 1, 2, -1, 0, 0});
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_EQ(runs[0].line, 0);
  EXPECT_EQ(runs[0].first, 1);
  EXPECT_EQ(runs[0].last, 3);
  EXPECT_EQ(runs[1].line, 1);
  EXPECT_EQ(runs[2].line, 2);
  EXPECT_EQ(runs[2].first, 7);
  EXPECT_EQ(runs[3].line, 0);
  EXPECT_EQ(runs[3].first, 9);
}

// Correct edges pass; a loop 50 m and 180° wrong forced in (Gaussian, high information) bends the
// lines it joins and fails them.
TEST(GraphCheck, PassesACorrectGraphAndNamesTheLinesAWrongLoopBends) {
  const Survey s = lawnmower(8);
  std::mt19937 rng(9);
  const auto [adjacent, loops] = registrations(s, rng);
  const std::vector<PoseGraphEdge> good = joined(s.odometry, joined(adjacent, loops));
  const GraphSolution solved = optimize_pose_graph(s.dr, good);
  const GraphCheck healthy = check_graph(solved.poses, good, s.line);
  EXPECT_TRUE(healthy.pass);
  EXPECT_EQ(healthy.lines.size(), 7u);
  EXPECT_TRUE(healthy.worst_lines.empty());
  EXPECT_EQ(healthy.lines[0].edges, 29);
  EXPECT_EQ(healthy.lines[0].dof, 87);

  const int a = 31 + 15, b = 3 * 31 + 15;  // mid line 1, mid line 3
  PoseGraphEdge forced{a, b, s.truth[a].inverse() * s.truth[b] * pose(50, 0, M_PI, 0),
                       information_from_sigmas({0.05, 0.05, 0.05}, {1e-3, 1e-3, 1e-3}), false};
  const std::vector<PoseGraphEdge> bent = joined(good, {forced});
  const GraphCheck broken = check_graph(optimize_pose_graph(s.dr, bent).poses, bent, s.line);
  EXPECT_FALSE(broken.pass);
  ASSERT_FALSE(broken.worst_lines.empty());
  const int worst = broken.lines[broken.worst_lines[0]].run.line;
  EXPECT_TRUE(worst == 1 || worst == 3) << "worst line " << worst;
}

// ---- the robust back end on a lawnmower with wrong loops ----------------------------------------

// PCM selection (with plausibility) over every registration, then a solve under DCS.
GraphSolution robust_solve(const Survey& s, const std::vector<PoseGraphEdge>& registrations_, const GraphConfig& config) {
  const LoopSelection selection = select_consistent_loops(candidates_of(registrations_, s.dr), DrNoiseModel(s.dr, config));
  std::vector<PoseGraphEdge> edges = s.odometry;
  for (int k : selection.kept) edges.push_back(registrations_[k]);
  return optimize_pose_graph(s.dr, edges, config);
}

TEST(RobustGraph, RecoversALawnmowerFromThirtyPercentWrongLoops) {
  for (unsigned seed : {21u, 22u, 23u}) {
    const Survey s = lawnmower(seed);
    std::mt19937 rng(seed + 100);
    const auto [adjacent, loops] = registrations(s, rng);
    std::vector<int> order(loops.size());
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), rng);
    const int wrong_count = static_cast<int>(std::lround(0.3 * loops.size()));
    std::vector<PoseGraphEdge> corrupted = loops, still_good;  // the loops left correct
    for (int k = 0; k < static_cast<int>(loops.size()); ++k) {
      if (k < wrong_count) corrupted[order[k]] = wrong(loops[order[k]], rng);
      else still_good.push_back(loops[order[k]]);
    }

    GraphConfig config;
    config.robust_kernel = RobustKernel::dcs;
    // The yardstick: the same solve given only the edges that are still correct.
    const GraphSolution good = optimize_pose_graph(s.dr, joined(s.odometry, joined(adjacent, still_good)), config);
    const GraphSolution robust = robust_solve(s, joined(adjacent, corrupted), config);
    const std::vector<PoseGraphEdge> plain_edges = joined(s.odometry, joined(adjacent, corrupted));
    const GraphSolution plain = optimize_pose_graph(s.dr, plain_edges);
    const double good_max = max_error(good.poses, s.truth), good_rms = rms_error(good.poses, s.truth);
    SCOPED_TRACE("seed " + std::to_string(seed) + ": " + std::to_string(loops.size()) + " loops, " +
                 std::to_string(wrong_count) + " wrong; DR max " + std::to_string(max_error(s.dr, s.truth)) +
                 " m, good max " + std::to_string(good_max) + " m, robust max " +
                 std::to_string(max_error(robust.poses, s.truth)) + " m, plain max " +
                 std::to_string(max_error(plain.poses, s.truth)) + " m");
    EXPECT_GT(max_error(s.dr, s.truth), 10.0) << "the test needs visible drift";
    EXPECT_LE(max_error(robust.poses, s.truth), 1.1 * good_max + 0.1);
    EXPECT_LE(rms_error(robust.poses, s.truth), 1.1 * good_rms + 0.1);
    EXPECT_GT(max_error(plain.poses, s.truth), 5.0 * good_max + 2.0) << "wrong loops must hurt a plain solve";

    // The pulls name a wrong loop as the hardest. (The per-line test does not fail here: under
    // Huber the wrong loops bend every line a little, well within Table 1's 5 m a step.)
    const GraphCheck check = check_graph(plain.poses, plain_edges, s.line);
    ASSERT_FALSE(check.registration_pulls.empty());
    const int hardest = check.registration_pulls[0].edge - static_cast<int>(s.odometry.size() + adjacent.size());
    EXPECT_TRUE(hardest >= 0 && std::find(order.begin(), order.begin() + wrong_count, hardest) != order.begin() + wrong_count)
        << "hardest pull: edge " << check.registration_pulls[0].edge;
  }
}

// The pipeline selects again after every batch, with the pairs' tests kept (KnownConflicts):
// batch after batch, the selection must be the one every pair computed afresh gives.
TEST(RobustGraph, KeptPairTestsSelectAsComputingEveryPair) {
  // As above: the first loop turned 10° (plausible, inconsistent), the last 180° (implausible).
  const Survey s = lawnmower(3);
  std::mt19937 rng(4);
  const auto [adjacent, loops] = registrations(s, rng);
  std::vector<PoseGraphEdge> edges = joined(adjacent, loops);
  edges.front().measured = edges.front().measured * pose(0, 0, 10 * kDeg, 0);
  edges.back().measured = edges.back().measured * pose(0, 0, M_PI, 0);
  std::vector<LoopCandidate> all = candidates_of(edges, s.dr);
  for (std::size_t k = 0; k < all.size(); ++k) all[k].id = static_cast<int>(k);
  const DrNoiseModel dr(s.dr, GraphConfig{});
  KnownConflicts known;
  int inconsistent = 0;
  for (std::size_t n = 5; n <= all.size(); n += 5) {
    const std::vector<LoopCandidate> batch(all.begin(), all.begin() + n);
    const LoopSelection fresh = select_consistent_loops(batch, dr);
    const LoopSelection kept = select_consistent_loops(batch, dr, {}, &known);
    ASSERT_EQ(kept.verdicts, fresh.verdicts) << n << " loops";
    ASSERT_EQ(kept.kept, fresh.kept) << n << " loops";
    inconsistent = static_cast<int>(std::count(fresh.verdicts.begin(), fresh.verdicts.end(), LoopVerdict::inconsistent));
  }
  EXPECT_GT(inconsistent, 0) << "a wrong loop must be tested against the others";

  // In any order, and with loops leaving the set and coming back, as constraints leave the graph.
  KnownConflicts shuffled;
  std::mt19937 order_rng(9);
  for (int round = 0; round < 6; ++round) {
    std::vector<LoopCandidate> some;
    std::bernoulli_distribution keep(0.7);
    for (const LoopCandidate& loop : all) {
      if (keep(order_rng)) some.push_back(loop);
    }
    std::shuffle(some.begin(), some.end(), order_rng);
    const LoopSelection fresh = select_consistent_loops(some, dr);
    const LoopSelection kept = select_consistent_loops(some, dr, {}, &shuffled);
    ASSERT_EQ(kept.verdicts, fresh.verdicts) << "round " << round;
    ASSERT_EQ(kept.kept, fresh.kept) << "round " << round;
  }
  std::vector<LoopCandidate> twice = {all[0], all[1], all[0]};
  EXPECT_THROW(select_consistent_loops(twice, dr, {}, &shuffled), std::invalid_argument);
}

// The graph's covariance of a pair (relative_covariances) with odometry alone is dead reckoning's,
// in its parametrisation (x, y, yaw in `from`'s level frame), both ways along the chain and across
// the turn; a registration between the two passes shrinks it for the pairs beside it.
TEST(DrNoise, TheGraphsCovarianceOfAPairIsDeadReckoningsUntilARegistrationTiesIt) {
  const std::vector<Eigen::Isometry3d> dr = out_and_back(15);
  GraphConfig config;
  config.dr_sigma_translation_m = {0.3, 0.3, 0.1};
  config.dr_sigma_rotation_rad = {1e-4, 1e-4, 3e-3};
  const DrNoiseModel model(dr, config);
  std::vector<PoseGraphEdge> edges;
  for (int k = 0; k + 1 < static_cast<int>(dr.size()); ++k) {
    edges.push_back({k, k + 1, dr[k].inverse() * dr[k + 1], odometry_information(config, k)});
  }
  const std::vector<std::pair<int, int>> pairs{{0, 12}, {3, 25}, {25, 3}, {29, 14}, {7, 8}};
  const auto graph = relative_covariances(dr, edges, config, pairs);
  ASSERT_TRUE(graph.has_value());
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const Eigen::Matrix3d expected = xy_yaw_block(model.covariance(pairs[k].first, pairs[k].second));
    EXPECT_TRUE((*graph)[k].isApprox(expected, 1e-4)) << pairs[k].first << "->" << pairs[k].second << "\n"
                                                      << (*graph)[k] << "\n" << expected;
  }

  // Nodes 4 and 25 face each other across the turn (out_and_back); tie them to a centimetre.
  edges.push_back({4, 25, dr[4].inverse() * dr[25], information_from_sigmas({0.01, 0.01, 0.01}, {1e-3, 1e-3, 1e-3})});
  edges.back().robust = true;
  const auto tied = relative_covariances(dr, edges, config, {{5, 24}});
  ASSERT_TRUE(tied.has_value());
  const double dr_sigma = std::sqrt(xy_yaw_block(model.covariance(5, 24)).topLeftCorner<2, 2>().trace());
  const double graph_sigma = std::sqrt((*tied)[0].topLeftCorner<2, 2>().trace());
  EXPECT_LT(graph_sigma, 0.3 * dr_sigma) << "a step of odometry each side of the tie, not the whole turn";
  EXPECT_GT(graph_sigma, 0.3) << "but those two steps' noise stays";
}

}  // namespace
}  // namespace bathyslam
