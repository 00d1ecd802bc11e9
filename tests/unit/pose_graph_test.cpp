#include "core/graph/pose_graph.h"

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

TEST(PoseGraph, OdometryAloneKeepsDeadReckoning) {
  std::vector<Eigen::Isometry3d> dr = {pose(0, 0, 0), pose(10, 1, 0.1), pose(19, 4, 0.3)};
  std::vector<PoseGraphEdge> edges;
  for (int i = 1; i < 3; ++i) edges.push_back({i - 1, i, dr[i - 1].inverse() * dr[i], Information6::Identity(), false});
  const GraphSolution solution = optimize_pose_graph(dr, edges);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(solution.poses[i].isApprox(dr[i], 1e-9));
}

}  // namespace
}  // namespace bathyslam
