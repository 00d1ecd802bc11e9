#include "core/eval/metrics.h"

#include <gtest/gtest.h>

#include "tests/unit/submap_errors.h"
#include "tests/unit/true_submaps.h"

namespace bathyslam {
namespace {

// Line 0 covers x in [0, 20), line 1 covers x in [10, 30) half a metre deeper: they share
// 10 x 20 cells of 1 m.
SubmapSet two_lines_half_a_metre_apart() {
  SubmapSet set;
  set.lines.resize(2);
  set.submaps.push_back(flat_patch(0, 0, 0, 0, 20, 20, -10.0f));
  set.submaps.push_back(flat_patch(1, 1, 10, 0, 20, 20, -10.5f));
  return set;
}

TEST(Consistency, TwoLinesOffsetByHalfAMetreVerticallyGiveHalfAMetre) {
  const SubmapSet set = two_lines_half_a_metre_apart();
  const std::vector<Eigen::Isometry3d> poses = poses_of(set);

  const ConsistencyReport report = consistency_error(set, poses);
  EXPECT_EQ(report.stats.count, 200u);
  EXPECT_NEAR(report.stats.rmse, 0.5, 1e-5);
  EXPECT_NEAR(report.stats.p99, 0.5, 1e-5);
  EXPECT_NEAR(report.stats.max, 0.5, 1e-5);
  // 0.5 m in bins of 0.02 m.
  EXPECT_EQ(report.histogram.counts[25], 200u);
}

TEST(Consistency, OneLineAloneHasNothingToCompareAndTurnsDoNotCount) {
  SubmapSet set;
  set.lines.resize(1);
  set.submaps.push_back(flat_patch(0, 0, 0, 0, 20, 20, -10.0f));
  set.submaps.push_back(flat_patch(1, -1, 0, 0, 20, 20, -12.0f));  // a turn over the same ground
  EXPECT_EQ(consistency_error(set, poses_of(set)).stats.count, 0u);
}

TEST(Consistency, CorrectedPosesRemoveTheOffset) {
  const SubmapSet set = two_lines_half_a_metre_apart();
  std::vector<Eigen::Isometry3d> poses = poses_of(set);
  poses[1].translation().z() += 0.5;
  EXPECT_NEAR(consistency_error(set, poses).stats.rmse, 0.0, 1e-5);
}

// Two surveys of one line each over the same patches (the second half a metre deeper, and 1 m
// deeper still where x < 15, a change): across counts every shared cell, or only those not
// changed; within has none (one line per survey).
TEST(SiteConsistency, ChangedCellsCanBeLeftOutOfAcross) {
  SubmapSet set = two_lines_half_a_metre_apart();
  set.survey_starts = {1};
  for (Submap& s : set.submaps) s.dr_pose.translation() += Eigen::Vector3d(-40, -40, 0);  // negative cells
  for (Eigen::Vector3f& p : set.submaps[1].points) {
    if (p.x() + 10 < 15) p.z() -= 1.0f;  // map x = 10 - 40 + submap x
  }
  const std::vector<Eigen::Isometry3d> poses = poses_of(set);
  const SiteConsistency all = site_consistency(set, poses);
  EXPECT_EQ(all.within.stats.count, 0u);
  EXPECT_EQ(all.across.stats.count, 200u);
  EXPECT_NEAR(all.across.stats.max, 1.5, 1e-5);
  // The changed cells' centres: x in (-30, -25), y in (-40, -20).
  const SiteConsistency unchanged = site_consistency(set, poses, {}, [](const Eigen::Vector2d& centre) {
    return centre.x() > -30 && centre.x() < -25 && centre.y() > -40 && centre.y() < -20;
  });
  EXPECT_EQ(unchanged.across.stats.count, 100u);
  EXPECT_NEAR(unchanged.across.stats.rmse, 0.5, 1e-5);
}

TEST(ErrorStats, KnownSeries) {
  const ErrorStats s = error_stats({3, 4, 0, 0});  // unordered on purpose
  EXPECT_DOUBLE_EQ(s.mean, 1.75);
  EXPECT_DOUBLE_EQ(s.rmse, 2.5);
  EXPECT_DOUBLE_EQ(s.max, 4);
  EXPECT_NEAR(s.std, std::sqrt(6.25 - 1.75 * 1.75), 1e-12);
}

// A trajectory that is the reference turned by 2 degrees about a far point and shifted: no error
// once aligned, metres of it unaligned; an error that no rotation explains stays.
TEST(TrajectoryError, AlignmentRemovesARigidTurnButNotAShapeError) {
  SubmapSet set;
  std::vector<Eigen::Isometry3d> estimate;
  const Eigen::Rotation2Dd turn(2.0 * M_PI / 180.0);
  for (int i = 0; i < 40; ++i) {
    Submap s;
    s.index = i;
    const Eigen::Vector2d truth(20.0 * (i % 20), 30.0 * (i / 20));
    Eigen::Isometry3d reference = Eigen::Isometry3d::Identity();
    reference.translation() << truth, -10.0;
    s.reference_pose = reference;
    set.submaps.push_back(s);
    Eigen::Isometry3d moved = reference;
    moved.translation().head<2>() = turn * (truth - Eigen::Vector2d(-500, 0)) + Eigen::Vector2d(-500, 0) + Eigen::Vector2d(3, -4);
    estimate.push_back(moved);
  }
  EXPECT_GT(error_stats(trajectory_errors(set, estimate)).rmse, 5.0);
  EXPECT_LT(error_stats(aligned_trajectory_errors(set, estimate)).max, 1e-6);

  estimate[10].translation().x() += 4.0;  // one pose off the rigid shape
  const ErrorStats aligned = error_stats(aligned_trajectory_errors(set, estimate));
  EXPECT_GT(aligned.max, 3.0);
  EXPECT_LT(aligned.max, 4.0 + 1e-6);
}

TEST(Metrics, TheP99sUpperBoundLiesJustAboveItByTheQuantilesOwnSamplingNoise) {
  std::vector<double> values;
  for (int i = 1; i <= 10000; ++i) values.push_back(i);
  // Rank 0.99 · 9999 + 2.33 · √(10000 · 0.99 · 0.01) = 9899.0 + 23.2.
  EXPECT_DOUBLE_EQ(quantile_upper_bound(values, 0.99, 2.33), 9923.0);
  EXPECT_DOUBLE_EQ(quantile_upper_bound(values, 0.99, 0.0), error_stats(values).p99);
  const std::vector<double> few = {1, 2, 3};
  EXPECT_DOUBLE_EQ(quantile_upper_bound(few, 0.99, 2.33), 3.0) << "never past the largest";
  EXPECT_DOUBLE_EQ(quantile_upper_bound({}, 0.99, 2.33), 0.0);
}

// Where each cell's error is its own (sounding noise), drawing the cells in blocks bounds the p99
// about as tightly as counting every cell; where a submap's cells move together (its pose error),
// the p99 of another map of the same quality could lie much higher, and the blocks say so.
TEST(Metrics, BlocksOfASubmapBoundTheP99ByWhatItsCorrelatedCellsAllow) {
  const ConsistencyConfig config;
  const SubmapSet independent = lines_with_submap_errors(0.0, 0.2, 1);
  const ConsistencyReport own = consistency_error(independent, poses_of(independent), config);
  const double own_blocks = p99_upper_by_blocks(independent, poses_of(independent), config, 20.0);
  EXPECT_GE(own_blocks, own.stats.p99);
  EXPECT_LT(own_blocks - own.stats.p99, 3 * (own.p99_upper - own.stats.p99) + 0.01);

  const SubmapSet correlated = lines_with_submap_errors(0.1, 0.02, 1);
  const ConsistencyReport moved = consistency_error(correlated, poses_of(correlated), config);
  const double moved_blocks = p99_upper_by_blocks(correlated, poses_of(correlated), config, 20.0);
  EXPECT_GT(moved_blocks - moved.stats.p99, 5 * (moved.p99_upper - moved.stats.p99)) << moved.stats.p99 << " " << moved.p99_upper << " " << moved_blocks << " " << moved.stats.max << " own " << own.stats.p99 << " " << own.p99_upper << " " << own_blocks;
  EXPECT_LE(moved_blocks, moved.stats.max);
  EXPECT_EQ(moved_blocks, p99_upper_by_blocks(correlated, poses_of(correlated), config, 20.0)) << "deterministic";
  EXPECT_NEAR(median_submap_side_m(correlated), 20.0, 0.3);
}

// Worked by hand: one block is all any draw can give, so the bound is that block's p99; blocks
// alike give the p99 itself; nothing to draw gives 0.
TEST(Metrics, TheBlockBoundOfOneBlockOrOfBlocksAlikeIsTheP99) {
  const ConsistencyConfig config;
  SubmapSet one;
  one.lines.resize(2);
  one.submaps.push_back(flat_patch(0, 0, 0, 0, 10, 10, -10.0f));
  one.submaps.push_back(flat_patch(1, 1, 0, 0, 10, 10, -10.25f));  // 100 cells 0.25 m apart
  const double p99 = consistency_error(one, poses_of(one), config).stats.p99;
  EXPECT_NEAR(p99, 0.25, 1e-5);
  EXPECT_EQ(p99_upper_by_blocks(one, poses_of(one), config, 100.0), p99);
  EXPECT_EQ(p99_upper_by_blocks(one, poses_of(one), config, 5.0), p99) << "four blocks alike";
  EXPECT_EQ(p99_upper_by_blocks(one, poses_of(one), config, 100.0, 0), 0.0);
  EXPECT_EQ(p99_upper_by_blocks(SubmapSet{}, {}, config, 100.0), 0.0);
  EXPECT_EQ(median_submap_side_m(SubmapSet{}), 0.0);
}

}  // namespace
}  // namespace bathyslam
