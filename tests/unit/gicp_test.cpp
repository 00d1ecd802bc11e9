#include "core/register/gicp.h"

#include <gtest/gtest.h>

#include "core/candidates/candidates.h"
#include "tests/unit/true_submaps.h"

namespace bathyslam {
namespace {

const SubmapSet& true_submaps() {
  static const SubmapSet set = true_small_submaps(4);
  return set;
}

double angle_deg(const Eigen::Isometry3d& t) { return Eigen::AngleAxisd(t.rotation()).angle() * 180 / M_PI; }

TEST(Gicp, RecoversAKnownOffsetBetweenAdjacentLineSubmaps) {
  const SubmapSet& set = true_submaps();
  const std::vector<Eigen::Isometry3d> poses = poses_of(set);
  // The well-overlapping pair on the roughest ground: GICP cannot see a horizontal offset on a
  // flat bottom (that is what the feature-aided path and the quality weights are for).
  const std::optional<CandidatePair> found = roughest_adjacent_pair(set);
  ASSERT_TRUE(found);
  const CandidatePair pair = *found;
  const Eigen::Isometry3d truth = poses[pair.target].inverse() * poses[pair.source];
  // The guess is off by 2 m, 1.5 m and 3 degrees of yaw.
  Eigen::Isometry3d offset = Eigen::Isometry3d::Identity();
  offset.translation() = Eigen::Vector3d(2.0, 1.5, 0.0);
  offset.linear() = Eigen::AngleAxisd(3.0 * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Isometry3d guess = offset * truth;

  const Cloud::Ptr target_all = voxel_filter(set.submaps[pair.target].points);
  const Cloud::Ptr source_all = voxel_filter(set.submaps[pair.source].points);
  const Cloud::Ptr target = crop_to_overlap(*target_all, *source_all, guess.inverse(), 1.0);
  const Cloud::Ptr source = crop_to_overlap(*source_all, *target_all, guess, 1.0);
  // Table 1's single pass lands near the minimum but stops short of it.
  const Registration table1 = register_gicp(target, source, guess);
  const Eigen::Isometry3d table1_error = truth.inverse() * table1.source_to_target;
  EXPECT_TRUE(table1.quality.converged);
  EXPECT_LT(table1_error.translation().norm(), 0.3) << "translation error " << table1_error.translation().transpose();
  EXPECT_LT(angle_deg(table1_error), 1.0);
  EXPECT_GT(table1.quality.overlap_points, 500u);

  // About the centroids with a refining pass it reaches the 0.1 m and 0.3 degrees.
  GicpConfig large_offset;
  large_offset.about_centroid = 1;
  large_offset.refine_correspondence_m = 1.0;
  const Registration r = register_gicp(target, source, guess, large_offset);
  const Eigen::Isometry3d error = truth.inverse() * r.source_to_target;
  EXPECT_TRUE(r.quality.converged);
  EXPECT_LT(error.translation().norm(), 0.1) << "translation error " << error.translation().transpose();
  EXPECT_LT(angle_deg(error), 0.3);
}

}  // namespace
}  // namespace bathyslam

namespace bathyslam {
namespace {

TEST(KeepDrRollPitch, KeepsGuessRollPitchAndMovesTheAnchorLikeTheRegistration) {
  Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();
  guess.linear() = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitX()))
                       .toRotationMatrix();
  guess.translation() = Eigen::Vector3d(1, 30, 0.5);
  // The registration turned 0.02 rad about z and, wrongly, 0.015 rad in roll.
  Eigen::Isometry3d registered = guess;
  registered.linear() = (Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(0.015, Eigen::Vector3d::UnitX())).toRotationMatrix() *
                        guess.rotation();
  registered.translation() += Eigen::Vector3d(0.4, -0.2, 0.1);
  const Eigen::Vector3d anchor(2, -15, 10);

  const Eigen::Isometry3d kept = keep_dr_roll_pitch(registered, guess, anchor);
  EXPECT_TRUE((kept * anchor).isApprox(registered * anchor, 1e-12));
  const Eigen::Matrix3d delta = kept.rotation() * guess.rotation().transpose();
  const Eigen::AngleAxisd turn(delta);
  EXPECT_NEAR(turn.angle(), 0.02, 1e-3) << "keeps the registration's yaw";
  EXPECT_NEAR(std::abs(turn.axis().z()), 1.0, 1e-9) << "and nothing but yaw";
}

}  // namespace
}  // namespace bathyslam
