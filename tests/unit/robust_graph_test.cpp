// The robust back end: DR noise and plausibility, pairwise loop consistency, the DCS kernel,
// the per-line check, and all of them against a lawnmower with wrong loop closures.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/graph/dr_noise.h"
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

// The first-order covariance against the spread of DR re-run with sampled step noise, both ways
// along the chain and across the turn: whitened by the model, the sample covariance is ≈ I.
TEST(DrNoise, CovarianceMatchesMonteCarloOfNoisyChains) {
  const std::vector<Eigen::Isometry3d> dr = out_and_back(15);
  const GraphConfig config;
  const DrNoiseModel model(dr, config);
  const std::vector<std::pair<int, int>> pairs = {{0, 12}, {3, 25}, {25, 3}, {29, 14}, {7, 8}};
  std::vector<std::vector<Vector6>> errors(pairs.size());
  std::mt19937 rng(11);
  for (int sample = 0; sample < 20000; ++sample) {
    const std::vector<Eigen::Isometry3d> chain = noisy_chain(dr, config, rng);
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const auto [from, to] = pairs[k];
      errors[k].push_back(pose_difference(chain[from].inverse() * chain[to], model.relative_pose(from, to)));
    }
  }
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    Covariance6 sample = Covariance6::Zero();
    for (const Vector6& e : errors[k]) sample += e * e.transpose() / errors[k].size();
    const Covariance6 predicted = model.covariance(pairs[k].first, pairs[k].second);
    const Eigen::LLT<Covariance6> llt(predicted);
    const Covariance6 inverse_root = llt.matrixL().solve(Covariance6::Identity());
    const Eigen::SelfAdjointEigenSolver<Covariance6> whitened(inverse_root * sample * inverse_root.transpose());
    EXPECT_GT(whitened.eigenvalues().minCoeff(), 0.93) << pairs[k].first << "->" << pairs[k].second;
    EXPECT_LT(whitened.eigenvalues().maxCoeff(), 1.07) << pairs[k].first << "->" << pairs[k].second;
  }
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

// Across 100 steps (2 km) yaw noise alone lets the end wander tens of metres sideways; across
// one step only the step's 5 m. The same sideways offset passes the first and not the second.
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
// origin its uncertainty sideways is the lever arm times the yaw's.
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

}  // namespace
}  // namespace bathyslam
