#include "core/graph/pose_graph.h"
#include "core/graph/relative_pose_cost.h"
#include "core/graph/relative_pose_error.h"

#include <ceres/autodiff_cost_function.h>
#include <ceres/manifold.h>
#include <ceres/product_manifold.h>
#include <gtest/gtest.h>

#include <random>

namespace bathyslam {
namespace {

Eigen::Isometry3d pose(double x, double y, double yaw) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = Eigen::Vector3d(x, y, -10.0);
  p.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return p;
}

// Two passes along a line, 30 m apart: odometry drifts in yaw, accurate cross-line edges pull
// the estimate back to the truth.
TEST(PoseGraph, RecoversAKnownTrajectoryFromDriftingOdometryAndCrossEdges) {
  std::vector<Eigen::Isometry3d> truth;
  for (int i = 0; i < 20; ++i) truth.push_back(pose(20.0 * i, 0, 0));
  for (int i = 19; i >= 0; --i) truth.push_back(pose(20.0 * i, 30.0, M_PI));

  std::mt19937 rng(5);
  std::normal_distribution<double> yaw_noise(0.0, 0.004);
  const GraphConfig config;
  const Information6 dr_info = information_from_sigmas(config.dr_sigma_translation_m, config.dr_sigma_rotation_rad);
  std::vector<PoseGraphEdge> edges;
  std::vector<Eigen::Isometry3d> dr = {truth[0]};
  for (std::size_t i = 1; i < truth.size(); ++i) {
    Eigen::Isometry3d rel = truth[i - 1].inverse() * truth[i];
    rel = rel * pose(0, 0, yaw_noise(rng)) * Eigen::Translation3d(0, 0, 10.0);  // yaw error only
    edges.push_back({static_cast<int>(i - 1), static_cast<int>(i), rel, dr_info, false});
    dr.push_back(dr.back() * rel);
  }
  const Information6 cross_info = information_from_sigmas({0.1, 0.1, 0.1}, {0.002, 0.002, 0.002});
  for (int i = 0; i < 20; ++i) {
    const int j = 39 - i;  // the pose of the second pass beside pose i
    edges.push_back({i, j, truth[i].inverse() * truth[j], cross_info, true});
  }

  auto max_error = [&](const std::vector<Eigen::Isometry3d>& poses) {
    double e = 0;
    for (std::size_t i = 0; i < poses.size(); ++i) e = std::max(e, (poses[i].translation() - truth[i].translation()).norm());
    return e;
  };
  const GraphSolution solution = optimize_pose_graph(dr, edges, config);
  EXPECT_TRUE(solution.converged);
  EXPECT_GT(max_error(dr), 3.0) << "the test needs visible drift";
  // The drift shared by both passes is only partly observable from cross edges: most of it goes.
  EXPECT_LT(max_error(solution.poses), 0.25 * max_error(dr));
  EXPECT_TRUE(solution.poses[0].isApprox(truth[0])) << "the first pose is fixed";
}

// A solve over a window: the poses before `first_free` stay exactly where they were, the edges
// into the window anchor it, and the window still moves to meet a cross edge.
TEST(PoseGraph, PosesBeforeTheFirstFreeOneAreHeld) {
  std::vector<Eigen::Isometry3d> truth, dr;
  for (int i = 0; i < 10; ++i) truth.push_back(pose(20.0 * i, 0, 0));
  const GraphConfig config;
  const Information6 dr_info = information_from_sigmas(config.dr_sigma_translation_m, config.dr_sigma_rotation_rad);
  std::vector<PoseGraphEdge> edges;
  dr.push_back(truth[0]);
  for (int i = 1; i < 10; ++i) {
    const Eigen::Isometry3d rel = truth[i - 1].inverse() * truth[i] * Eigen::Translation3d(0.5, 0.4, 0);  // drifts
    edges.push_back({i - 1, i, rel, dr_info, false});
    dr.push_back(dr.back() * rel);
  }
  const Information6 cross_info = information_from_sigmas({0.05, 0.05, 0.05}, {0.002, 0.002, 0.002});
  edges.push_back({2, 8, truth[2].inverse() * truth[8], cross_info, true});

  const GraphSolution whole = optimize_pose_graph(dr, edges, config);
  const GraphSolution window = optimize_pose_graph(dr, edges, config, 5);
  for (int i = 0; i < 5; ++i) {
    EXPECT_TRUE(window.poses[i].isApprox(dr[i], 1e-12)) << "pose " << i << " is held";
  }
  EXPECT_FALSE(whole.poses[4].isApprox(dr[4], 1e-3)) << "unheld, the cross edge moves it";
  // The cross edge still places pose 8 relative to pose 2, which now cannot move.
  const Eigen::Vector3d wanted = (dr[2] * (truth[2].inverse() * truth[8])).translation();
  EXPECT_LT((window.poses[8].translation() - wanted).norm(), 0.2);
  EXPECT_GT((dr[8].translation() - wanted).norm(), 2.0) << "the test needs drift";
}

// A registration 30 m to the side whose yaw is 1 degree off but which puts the overlap exactly
// where it is: compared at the overlap (the anchor), the loose yaw does not move the pose.
TEST(PoseGraph, AnAnchoredEdgeComparesTranslationAtItsAnchor) {
  const std::vector<Eigen::Isometry3d> truth = {pose(0, 0, 0), pose(0, 30, 0)};
  const Eigen::Vector3d anchor(0, -15, 10);  // overlap centroid, node 1's frame
  const Eigen::Isometry3d true_relative = truth[0].inverse() * truth[1];
  // Turned 1 degree about the anchor: the anchor lands where it should, the origin 0.26 m off.
  const Eigen::Isometry3d turned = Eigen::Translation3d(true_relative * anchor) *
                                   Eigen::AngleAxisd(M_PI / 180, Eigen::Vector3d::UnitZ()) *
                                   Eigen::Translation3d(-(true_relative * anchor)) * true_relative;
  const Information6 dr_info = information_from_sigmas({5, 5, 1}, {1e-4, 1e-4, 1e-4});  // trusts yaw
  const Information6 registration_info = information_from_sigmas({0.05, 0.05, 0.05}, {0.1, 0.1, 0.1});
  auto solve = [&](const Eigen::Vector3d& edge_anchor) {
    std::vector<PoseGraphEdge> edges = {{0, 1, true_relative, dr_info, false},
                                        {0, 1, turned, registration_info, true, edge_anchor}};
    Eigen::Isometry3d start = truth[1];
    start.translation() += Eigen::Vector3d(3, -2, 0);
    return optimize_pose_graph({truth[0], start}, edges).poses[1];
  };
  EXPECT_LT((solve(anchor).translation() - truth[1].translation()).norm(), 0.01);
  EXPECT_GT((solve(Eigen::Vector3d::Zero()).translation() - truth[1].translation()).norm(), 0.2)
      << "compared at the origin, the 1 degree becomes a quarter metre";
}

// A flat-ground registration observes depth but not where it is: with zero information in x,
// y and yaw, its (wrong) horizontal measurement must not move the pose, its depth must, and
// that holds on a vehicle that rolls and pitches (the error is taken in a level frame).
TEST(PoseGraph, AnEdgeWithZeroHorizontalInformationCorrectsDepthOnly) {
  for (const double tilt_deg : {0.0, 1.0}) {
    Eigen::Isometry3d a = pose(0, 0, 0.3), b = pose(20, 0, 0.3);
    const Eigen::Matrix3d tilt = (Eigen::AngleAxisd(tilt_deg * M_PI / 180, Eigen::Vector3d::UnitX()) *
                                  Eigen::AngleAxisd(-tilt_deg * M_PI / 180, Eigen::Vector3d::UnitY())).toRotationMatrix();
    a.linear() = a.linear() * tilt;
    b.linear() = b.linear() * tilt;
    Eigen::Isometry3d dr = b;
    dr.translation().z() += 0.8;
    Eigen::Isometry3d flat = b;
    flat.translation() += Eigen::Vector3d(15, -10, 0);  // 18 m wrong along the (level) bottom, depth right
    Information6 depth_only = information_from_sigmas({0.1, 0.1, 0.05}, {0.002, 0.002, 0.004});
    for (int k : {0, 1, 5}) depth_only(k, k) = 0;
    const std::vector<PoseGraphEdge> edges = {
        {0, 1, a.inverse() * dr, information_from_sigmas({5, 5, 1}, {1e-4, 1e-4, 1e-2}), false},
        {0, 1, a.inverse() * flat, depth_only, true}};
    const GraphSolution solution = optimize_pose_graph({a, dr}, edges);
    ASSERT_TRUE(solution.converged);
    const Eigen::Vector3d p = solution.poses[1].translation();
    EXPECT_NEAR(p.x(), 20.0, 0.01) << "tilt " << tilt_deg;
    EXPECT_NEAR(p.y(), 0.0, 0.01) << "tilt " << tilt_deg;
    EXPECT_NEAR(p.z(), b.translation().z(), 0.01) << "depth follows the registration; tilt " << tilt_deg;
  }
}

TEST(PoseGraph, OdometryAloneKeepsDeadReckoning) {
  std::vector<Eigen::Isometry3d> dr = {pose(0, 0, 0), pose(10, 1, 0.1), pose(19, 4, 0.3)};
  std::vector<PoseGraphEdge> edges;
  for (int i = 1; i < 3; ++i) edges.push_back({i - 1, i, dr[i - 1].inverse() * dr[i], Information6::Identity(), false});
  const GraphSolution solution = optimize_pose_graph(dr, edges);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(solution.poses[i].isApprox(dr[i], 1e-9));
}

}  // namespace
}  // namespace bathyslam

namespace bathyslam {
namespace {

// The same residual as relative_pose_error, for Ceres to differentiate.
struct AutodiffRelativePose {
  Eigen::Vector3d anchor, anchor_measured;
  Eigen::Quaterniond q_measured;
  Information6 sqrt_information;
  template <typename T>
  bool operator()(const T* a, const T* b, T* residuals) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_a(a), p_b(b);
    const Eigen::Map<const Eigen::Quaternion<T>> q_a(a + 3), q_b(b + 3);
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residuals);
    r = sqrt_information.cast<T>() * relative_pose_error<T>(p_a, q_a, p_b, q_b, anchor, anchor_measured, q_measured);
    return true;
  }
};

Eigen::Matrix<double, 7, 1> node_of(const Eigen::Isometry3d& pose) {
  Eigen::Matrix<double, 7, 1> node;
  node << pose.translation(), Eigen::Quaterniond(pose.rotation()).coeffs();
  return node;
}

// The written-out Jacobian is the derivative of the residual along the nodes' manifold: on
// poses rolled, pitched and turned every way, with measurements a tenth of a radian and metres
// off (so the rotation error is far from identity), it matches automatic differentiation.
TEST(PoseGraph, RelativePoseJacobianIsTheResidualsDerivativeOnTheManifold) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto random_pose = [&](double tilt, double reach) {
    Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
    p.linear() = (Eigen::AngleAxisd(M_PI * unit(rng), Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(tilt * unit(rng), Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(tilt * unit(rng), Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    p.translation() = reach * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    return p;
  };
  const ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold> manifold;
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Isometry3d from = random_pose(0.3, 500), to = random_pose(0.3, 500);
    PoseGraphEdge edge{0, 1, from.inverse() * to * random_pose(0.1, 2).rotate(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ())),
                       Information6::Identity(), true, 50 * Eigen::Vector3d(unit(rng), unit(rng), unit(rng))};
    Information6 spread = Information6::Random();
    edge.information = spread * spread.transpose() + Information6::Identity();
    const AutodiffRelativePose reference{edge.anchor, edge.measured * edge.anchor,
                                         Eigen::Quaterniond(edge.measured.rotation()).normalized(),
                                         square_root(edge.information)};
    const ceres::AutoDiffCostFunction<AutodiffRelativePose, 6, 7, 7> autodiff(new AutodiffRelativePose(reference));
    const RelativePoseCost written(edge);

    const Eigen::Matrix<double, 7, 1> a = node_of(from), b = node_of(to);
    const double* parameters[] = {a.data(), b.data()};
    Eigen::Matrix<double, 6, 1> r_written, r_autodiff;
    Eigen::Matrix<double, 6, 7, Eigen::RowMajor> ja_written, jb_written, ja_autodiff, jb_autodiff;
    double* written_jacobians[] = {ja_written.data(), jb_written.data()};
    double* autodiff_jacobians[] = {ja_autodiff.data(), jb_autodiff.data()};
    ASSERT_TRUE(written.Evaluate(parameters, r_written.data(), written_jacobians));
    ASSERT_TRUE(autodiff.Evaluate(parameters, r_autodiff.data(), autodiff_jacobians));
    EXPECT_LT((r_written - r_autodiff).norm(), 1e-9 * (1 + r_autodiff.norm()));

    Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus_a, plus_b;
    manifold.PlusJacobian(a.data(), plus_a.data());
    manifold.PlusJacobian(b.data(), plus_b.data());
    const Eigen::Matrix<double, 6, 6> expected_a = ja_autodiff * plus_a, expected_b = jb_autodiff * plus_b;
    EXPECT_LT((ja_written * plus_a - expected_a).norm(), 1e-8 * expected_a.norm()) << "trial " << trial;
    EXPECT_LT((jb_written * plus_b - expected_b).norm(), 1e-8 * expected_b.norm()) << "trial " << trial;
    // With one node held, Ceres asks for the other's Jacobian alone.
    double* only_b[] = {nullptr, jb_written.data()};
    ASSERT_TRUE(written.Evaluate(parameters, r_written.data(), only_b));
    EXPECT_LT((jb_written * plus_b - expected_b).norm(), 1e-8 * expected_b.norm());
  }
}

}  // namespace
}  // namespace bathyslam
