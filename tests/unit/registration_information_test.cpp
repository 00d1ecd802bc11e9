#include "core/register/registration_information.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <functional>
#include <random>

#include "core/register/coarse_to_fine.h"
#include "tests/unit/synthetic_terrain.h"

namespace bathyslam {
namespace {

using Elevation = std::function<double(const Eigen::Vector2d&)>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

const Vector6 kBestSigmas = (Vector6() << 0.1, 0.1, 0.05, 0.002, 0.002, 0.004).finished();
constexpr double kFullShare = 0.03, kZeroShare = 0.012;  // QualityConfig's defaults

Eigen::Isometry3d pose(double x, double y, double yaw_deg, double roll_deg = 0) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = Eigen::Vector3d(x, y, 0);
  p.linear() = (Eigen::AngleAxisd(yaw_deg * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(roll_deg * M_PI / 180, Eigen::Vector3d::UnitX())).toRotationMatrix();
  return p;
}

// Soundings on a grid over the world rectangle [lo, hi], with vertical noise, in the frame
// whose pose in the world is `frame` (z down, as submaps store them).
Cloud::Ptr soundings(const Elevation& elevation, const Eigen::Isometry3d& frame, const Eigen::Vector2d& lo,
                     const Eigen::Vector2d& hi, double spacing_m, double noise_m, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_m);
  auto cloud = std::make_shared<Cloud>();
  for (double x = lo.x(); x <= hi.x(); x += spacing_m) {
    for (double y = lo.y(); y <= hi.y(); y += spacing_m) {
      const Eigen::Vector3f p = (frame.inverse() * Eigen::Vector3d(x, y, -(elevation({x, y}) + noise(rng)))).cast<float>();
      cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    }
  }
  return cloud;
}

struct Overlap {
  Cloud::Ptr target, source;
  Eigen::Isometry3d truth;  // source to target
  Eigen::Vector3d anchor;   // source overlap's centroid, as register_direct takes it
};

// Two 30 x 30 m submaps of `elevation` overlapping by 20 x 30 m, the source turned 25 degrees;
// each cropped to the overlap as register_direct does.
Overlap overlap_of(const Elevation& elevation, double spacing_m, double noise_m,
                   const Eigen::Isometry3d& target_frame = Eigen::Isometry3d::Identity()) {
  const Eigen::Isometry3d source_frame = pose(20, 15, 25);
  Overlap o;
  o.truth = target_frame.inverse() * source_frame;
  const Cloud::Ptr target = soundings(elevation, target_frame, {0, 0}, {30, 30}, spacing_m, noise_m, 1);
  const Cloud::Ptr source = soundings(elevation, source_frame, {10.13, 0.17}, {40, 30}, spacing_m, noise_m, 2);
  o.target = crop_to_overlap(*target, *source, o.truth.inverse(), 1.0);
  o.source = crop_to_overlap(*source, *target, o.truth, 1.0);
  o.anchor = centroid(*o.source);
  return o;
}

double flat(const Eigen::Vector2d&) { return -10.0; }

const Eigen::Vector2d kAcrossCrests(std::cos(0.3), std::sin(0.3));

double sand_waves(const Eigen::Vector2d& p) {  // 10 m wavelength, 0.5 m amplitude
  return -10.0 + 0.5 * std::sin(2 * M_PI * kAcrossCrests.dot(p) / 10.0);
}

Elevation mounds() {
  static const SyntheticTerrain terrain = SyntheticTerrain::with_mounds(21);
  return [](const Eigen::Vector2d& p) { return terrain.elevation(p); };
}

// Information per axis as a share of a perfect registration's (quality weight 1).
Information6 observed(const Overlap& o, const Eigen::Matrix3d& level_from_target = Eigen::Matrix3d::Identity()) {
  const GicpHessian h = gicp_hessian(*o.target, *o.source, o.truth, o.anchor, GicpConfig{});
  return observed_information(rotated(h, level_from_target), 1.0, kBestSigmas, kFullShare, kZeroShare);
}

Vector6 shares(const Information6& information) { return information.diagonal().cwiseProduct(kBestSigmas.cwiseAbs2()); }

double horizontal_share(const Information6& information, const Eigen::Vector2d& direction) {
  return direction.dot(information.topLeftCorner<2, 2>() * direction) * kBestSigmas(0) * kBestSigmas(0);
}

// Moves the source by (δt, δθ): translation of the anchor, then a turn about it, both in the
// target frame; the pose graph's anchored edge takes its error the same way.
Eigen::Isometry3d perturbed(const Eigen::Isometry3d& source_to_target, const Eigen::Vector3d& anchor, const Vector6& delta) {
  const Eigen::Vector3d c = source_to_target * anchor;
  const Eigen::Vector3d turn = delta.tail<3>();
  const Eigen::Matrix3d r = turn.norm() > 0 ? Eigen::AngleAxisd(turn.norm(), turn.normalized()).toRotationMatrix()
                                            : Eigen::Matrix3d::Identity();
  Eigen::Isometry3d d = Eigen::Isometry3d::Identity();
  d.linear() = r;
  d.translation() = c + delta.head<3>() - r * c;
  return d * source_to_target;
}

// The central second difference of the cost over fixed correspondences, against Jᵀ M J, entry
// by entry as a share of the geometric mean of the two diagonal entries (units differ).
double largest_hessian_error(const std::vector<GicpTerm>& terms, const Eigen::Isometry3d& solution,
                             const Eigen::Vector3d& anchor) {
  const Matrix6 h = gicp_hessian(terms, solution, anchor).hessian;
  const Vector6 step = (Vector6() << 1e-3, 1e-3, 1e-3, 1e-4, 1e-4, 1e-4).finished();
  auto cost = [&](int i, double si, int j, double sj) {
    Vector6 delta = Vector6::Zero();
    delta(i) += si * step(i);
    delta(j) += sj * step(j);
    return gicp_cost(terms, perturbed(solution, anchor, delta));
  };
  Matrix6 numeric;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      numeric(i, j) = (cost(i, 1, j, 1) - cost(i, 1, j, -1) - cost(i, -1, j, 1) + cost(i, -1, j, -1)) /
                      (4 * step(i) * step(j));
    }
  }
  const Vector6 scale = h.diagonal().cwiseSqrt().cwiseInverse();
  return (scale.asDiagonal() * (numeric - h) * scale.asDiagonal()).cwiseAbs().maxCoeff();
}

// A small problem: 12 x 12 m of mounds on a 0.5 m grid, the anchor away from both origins.
struct SmallProblem {
  std::vector<GicpTerm> terms;
  Eigen::Isometry3d solution = pose(18, 17, 10);
  Eigen::Vector3d anchor{-2.0, 1.5, 10.0};
};

SmallProblem small_problem(const Eigen::Vector2d& source_grid_origin, uint64_t source_seed) {
  SmallProblem p;
  const Cloud::Ptr target = soundings(mounds(), Eigen::Isometry3d::Identity(), {12, 12}, {24, 24}, 0.5, 0.02, 1);
  const Cloud::Ptr source = soundings(mounds(), p.solution, source_grid_origin, {24, 24}, 0.5, 0.02, source_seed);
  GicpConfig config;
  config.max_correspondence_m = 1.0;
  p.terms = gicp_terms(*target, *source, p.solution, config);
  return p;
}

TEST(GicpHessian, IsExactlyTheCostsSecondDerivativeWhereTheResidualsVanish) {
  // The source samples the very soundings of the target: every residual is zero at the
  // solution, where Gauss–Newton's Hessian is the exact one; this checks the Jacobian.
  const SmallProblem p = small_problem({12, 12}, 1);
  ASSERT_GT(p.terms.size(), 400u);
  EXPECT_LT(largest_hessian_error(p.terms, p.solution, p.anchor), 1e-3);
}

TEST(GicpHessian, IsCloseToTheCostsSecondDerivativeOnDifferentSoundings) {
  // Different grids and noise: nearest neighbours lie up to a quarter metre apart along the
  // bottom, and Gauss–Newton leaves out the terms those residuals carry.
  const SmallProblem p = small_problem({12.2, 12.3}, 2);
  ASSERT_GT(p.terms.size(), 400u);
  EXPECT_LT(largest_hessian_error(p.terms, p.solution, p.anchor), 0.05);
}

TEST(ObservedInformation, AFlatBottomObservesDepthRollAndPitchOnly) {
  const Vector6 s = shares(observed(overlap_of(flat, 0.4, 0.02)));
  for (int k : {0, 1, 5}) EXPECT_LT(s(k), 1e-3) << "x, y, yaw: axis " << k;
  for (int k : {2, 3, 4}) EXPECT_GT(s(k), 0.95) << "z, roll, pitch: axis " << k;
}

TEST(ObservedInformation, NoiseOnAFlatBottomIsNotTakenForRelief) {
  // 0.1 m of noise on a 0.25 m grid tilts each point's normal by a few degrees.
  const Vector6 s = shares(observed(overlap_of(flat, 0.25, 0.1)));
  for (int k : {0, 1, 5}) EXPECT_LT(s(k), 1e-3) << "x, y, yaw: axis " << k;
  for (int k : {2, 3, 4}) EXPECT_GT(s(k), 0.95) << "z, roll, pitch: axis " << k;
}

TEST(ObservedInformation, SandWavesObserveAcrossTheirCrestsNotAlong) {
  const Information6 information = observed(overlap_of(sand_waves, 0.4, 0.02));
  const Eigen::Vector2d along(-kAcrossCrests.y(), kAcrossCrests.x());
  const double across_share = horizontal_share(information, kAcrossCrests);
  EXPECT_GT(across_share, 0.9);
  EXPECT_LT(horizontal_share(information, along), 0.01 * across_share);
  const Vector6 s = shares(information);
  for (int k : {2, 3, 4, 5}) EXPECT_GT(s(k), 0.9) << "z, roll, pitch, yaw (it moves points across crests): axis " << k;
}

TEST(ObservedInformation, MoundsObserveEveryDirection) {
  const Vector6 s = shares(observed(overlap_of(mounds(), 0.4, 0.02)));
  for (int k = 0; k < 6; ++k) EXPECT_GT(s(k), 0.2) << "axis " << k;
}

TEST(ObservedInformation, IsNeverMoreThanTheQualityInformation) {
  for (const Elevation& elevation : {Elevation(flat), Elevation(sand_waves), mounds()}) {
    const Overlap o = overlap_of(elevation, 0.4, 0.02);
    const GicpHessian h = gicp_hessian(*o.target, *o.source, o.truth, o.anchor, {});
    const Information6 information = observed_information(h, 0.3, kBestSigmas, kFullShare, kZeroShare);
    const Vector6 root_best = kBestSigmas.cwiseInverse() * std::sqrt(0.3);
    // w·σ⁻² - Ω must be positive semi-definite: no direction, axis or not, gets more.
    const Matrix6 slack = Matrix6(root_best.cwiseAbs2().asDiagonal()) - information;
    const Matrix6 whitened = kBestSigmas.asDiagonal() * slack * kBestSigmas.asDiagonal();
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix6>(whitened).eigenvalues().minCoeff(), -1e-9);
  }
}

TEST(ObservedInformation, IsTakenInTheLevelFrameOfATiltedTarget) {
  // The target submap's frame rolls 1 degree: in it the flat bottom is tilted, and a 20 m error
  // along the bottom would show 0.35 m of itself as depth.
  const Eigen::Isometry3d tilted = pose(0, 0, 0, 1.0);
  const Overlap o = overlap_of(flat, 0.4, 0.02, tilted);
  const Vector6 level = shares(observed(o, tilted.rotation()));
  for (int k : {0, 1, 5}) EXPECT_LT(level(k), 1e-3) << "x, y, yaw: axis " << k;
  for (int k : {2, 3, 4}) EXPECT_GT(level(k), 0.95) << "z, roll, pitch: axis " << k;
  EXPECT_GT(shares(observed(o))(1), 1e-3) << "in the tilted frame, y looks observed";
}

// The observable floor (bench_oracle_graph --observable) gives each pair, at the truth and without
// registering, the information its overlap supports: none horizontally on a flat bottom, some
// in every direction over mounds, and the truth itself as the measurement.
TEST(ObserveAt, GivesTheInformationTheOverlapSupportsAtTheTruth) {
  GicpConfig gicp;
  for (const bool textured : {false, true}) {
    const Overlap o = overlap_of(textured ? mounds() : Elevation(flat), 0.4, 0.02);
    const auto target = prepare_gicp_cloud(*o.target, gicp), source = prepare_gicp_cloud(*o.source, gicp);
    const PairRegistration seen = observe_at(*target, *source, o.truth, gicp, 1.0);
    ASSERT_GT(seen.hessian.correspondences, 400u) << textured;
    EXPECT_TRUE(seen.registration.source_to_target.isApprox(o.truth)) << "observed, not registered";
    EXPECT_GT(seen.registration.quality.fitness, 0.9);
    const Vector6 s = shares(observed_information(seen.hessian, 1.0, kBestSigmas, kFullShare, kZeroShare));
    for (int k : {0, 1, 5}) {
      if (textured) {
        EXPECT_GT(s(k), 0.2) << "mounds, axis " << k;
      } else {
        EXPECT_LT(s(k), 1e-3) << "flat, axis " << k;
      }
    }
  }
}

}  // namespace
}  // namespace bathyslam
