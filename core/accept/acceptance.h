#pragma once
// accept: whether a registration becomes a graph edge (Table 1 (b)), and the quality-aware
// information matrix it enters the graph with (section 4).
#include <string>

#include <Eigen/Geometry>

#include "core/accept/rejection.h"
#include "core/graph/pose_graph.h"
#include "core/register/coarse_to_fine.h"
#include "core/types/fields.h"

namespace bathyslam {

struct AcceptanceConfig {  // Table 1 (b)
  double min_inlier_ratio = 0.25;
  double max_overlap_mse_m2 = 5.0;
  int min_overlap_points = 500;
  double max_translation_m = 100.0;  // how far the registration may move the source from DR
  // Uniqueness (feature-aided path): a pair whose best distinct alternative alignment has at
  // least this share of the winner's RANSAC inliers has no unique solution (a periodic seabed,
  // parallel ridges) and is refused. 0 turns the test off.
  double max_competitor_ratio = 0.5;
  // Uniqueness (feature-aided path, register/uniqueness.h): refused unless every other
  // horizontal offset of the terrain within reach fits at least this many times worse (in mean
  // squared misfit) than the answer, i.e. with an RMS misfit 5x the answer's: correct answers
  // and aliases a wavelength off fall far apart on either side of it (docs/results/robustness.md).
  // With robustness.alias_from_prior (on) it is only where such an answer stands outright; below
  // it dead reckoning judges the competitors (resolve_alias). 0 turns the test off.
  double min_distinctness = 25.0;

  template <typename Field>
  void fields(Field&& field) {
    field("min_inlier_ratio", min_inlier_ratio, 0, 1);
    field("max_overlap_mse_m2", max_overlap_mse_m2, 0, 1000);
    field("min_overlap_points", min_overlap_points, 0, 10000000);
    field("max_translation_m", max_translation_m, 0, 1e5);
    field("max_competitor_ratio", max_competitor_ratio, 0, 1);
    field("min_distinctness", min_distinctness, 0, 1e6);
  }
};

// kNone when accepted; otherwise the first failed test. A loop closure spans the drift of a line
// or more, wider than GICP's basin from dead reckoning: only the feature-aided path may close
// one (section 3.4, coarse to fine).
Rejection rejection_of(const PairRegistration& r, const Eigen::Isometry3d& guess, const AcceptanceConfig& config,
                       bool loop_closure);

struct QualityConfig {
  // Information of a perfect registration, compared at the overlap (the edge's anchor).
  Eigen::Vector3d best_sigma_translation_m{0.1, 0.1, 0.05};
  // Yaw: a registration that places an overlap some 20 m across to 0.1 m knows its turn to about
  // 0.1 m over a 10 m lever, 0.01 rad; tighter made correct edges sit sigmas off in yaw
  // (docs/results/robustness.md).
  Eigen::Vector3d best_sigma_rotation_rad{0.002, 0.002, 0.01};
  // Share of that information in x, y and yaw that a direct-path edge keeps. The switch sends
  // a pair down the direct path when its overlap has too few features to match, and there
  // GICP's horizontal answer is its starting guess: such edges carry the guess's error (metres
  // to tens of metres, docs/results/slam-results.md) with a good residual. They constrain depth,
  // roll and pitch; the horizontal comes from dead reckoning and feature-aided edges.
  double direct_horizontal_share = 0.0;
  // Nor does the direct path know where along the bottom its depth was measured: on sloping,
  // rippled or rough ground a depth taken a few metres off is a different depth. Its depth
  // information is capped at what the relief around the answer allows (the uniqueness probe's
  // local cost, as a variance); on a flat bottom that is no cap at all. 0 turns the cap off.
  bool direct_depth_from_relief = true;
  // 1: the information's shape comes from what the registration observed, the GICP cost's
  // Hessian (observed_information), instead of the diagonal above; direct_horizontal_share
  // then no longer applies, the Hessian telling flat overlaps from textured ones itself. Needs
  // the registration's Hessian (CoarseToFineConfig::hessian).
  bool information_from_hessian = true;
  // observed_information's shares: a direction with at least `hessian_full_share` of the
  // best-observed one's (whitened) curvature is fully observed, one with less than
  // `hessian_zero_share` not at all (sounding noise on a flat bottom reaches ~0.01).
  double hessian_full_share = 0.03;
  double hessian_zero_share = 0.012;
  // A direct registration's horizontal answer is the overlap's only if GICP comes back to it from
  // other starts: two more, this share of registration.gicp.max_correspondence_m to either side of
  // the guess, must land within what the answer's information claims (χ²₃ at 99.9 % on x, y and
  // yaw), or the answer is where its start fell and keeps depth, roll and pitch only. 0: not
  // checked.
  double start_check_share = 0.5;
  // Nor is it the overlap's when the terrain itself fits this many times better (in mean squared
  // misfit) a few metres away (Uniqueness::nearby_improvement): GICP stopped short of the
  // bottom of the basin. 4 is an RMS misfit twice the nearby one's. 0: not checked.
  double max_nearby_improvement = 4.0;
  // A direct registration's turn: GICP turns weakly textured overlaps 2-4 degrees off with a
  // good fit, 3-5 sigma of the Hessian's yaw (`lake` paper seed 2: 7 adjacent edges; crossing
  // loops on `small`). 0: it keeps its position at the anchor, depth, roll and pitch, and the
  // turn between lines comes from several edges' positions and the feature-aided edges.
  bool direct_yaw = false;
  // Where doubt or a plausible alias would take a direct answer's position away, widen it
  // instead (widened_by_doubt, resolve_alias): nothing along a direction GICP does not come
  // back along, or along which plausible competitors run on past the probe, and the scatter of
  // the other starts' landings, the nearby better fit or the plausible competitors added to the
  // covariance of the rest. On `small` sand waves and channels it lowers the consistency RMSE
  // 1.5-5x; widening along an alias line needs widen_min_distinctness below. 0: no horizontal
  // information where doubt or an alias would widen it (docs/slam-every-seabed.md).
  bool doubt_widens = true;
  // Widening along a line of plausible competitors (resolve_alias) trusts dead reckoning to have
  // ruled out every basin off the line. Where the best other local minimum the probe found (on
  // the line or off it, plausible or not) fits nearly as well as the answer
  // (Uniqueness::distinctness under this; 2 is an RMS misfit within 1.4x the answer's), the
  // answer itself may be an alias, and an estimate of the noise built from such answers is no
  // evidence against it: the answer keeps no horizontal information. An answer whose every
  // competitor dead reckoning rules out keeps its own information whatever this says. On `small`
  // sand waves and channels every edge off by more than 2 m that widening let through (without
  // direct_loops' reach test) had distinctness 0.47-1.41 (docs/slam-every-seabed.md). 0: not
  // checked.
  double widen_min_distinctness = 2.0;
  // A feature-aided answer less distinct than acceptance.min_distinctness whose competitors dead
  // reckoning does not all rule out is judged as a direct answer there would be (widened along
  // the plausible ones, or depth, roll and pitch only; its turn marginalised out and its depth
  // capped by the relief, as a direct answer's) instead of refused. Its features chose among the
  // competitors, and in every kept `small` matrix and `lake` report each one so refused was within
  // 0.5 m of the truth (32-41 a matrix pass, 5 on `lake`); what it keeps holds at any competitor
  // dead reckoning allows. Unlike a direct answer it has no start check (its start came from the
  // features). 0: refused, as before 2026-12-07.
  bool feature_aliases_as_direct = true;
  // A direct answer keeps no yaw, so the DR gate cannot see its turn; but where GICP turned the
  // overlap further from dead reckoning's heading than the heading noise allows (the squared turn
  // over DR's yaw variance between the two submaps above this: 25 is 5σ), its position was found
  // together with a wrong turn and keeps no horizontal information (`small` channel seed 5: a loop
  // turned 4.4° and 0.8 m off at 7σ under two drifts; seeds 1–3 and 4–6 otherwise all but
  // unchanged, docs/slam-every-seabed.md). Judged again under each noise estimate. 0: not tested.
  double max_turn_chi2 = 25.0;

  template <typename Field>
  void fields(Field&& field) {
    xyz("best_sigma_translation_m", best_sigma_translation_m, 1e-4, 1e5, field);
    rpy("best_sigma_rotation_rad", best_sigma_rotation_rad, 1e-6, 10, field);
    field("direct_horizontal_share", direct_horizontal_share, 0, 1);
    field("direct_depth_from_relief", direct_depth_from_relief, 0, 1);
    field("information_from_hessian", information_from_hessian, 0, 1);
    field("hessian_full_share", hessian_full_share, 1e-6, 1);
    field("hessian_zero_share", hessian_zero_share, 0, 1);
    field("start_check_share", start_check_share, 0, 10);
    field("max_nearby_improvement", max_nearby_improvement, 0, 1e6);
    field("direct_yaw", direct_yaw, 0, 1);
    field("doubt_widens", doubt_widens, 0, 1);
    field("widen_min_distinctness", widen_min_distinctness, 0, 1e6);
    field("feature_aliases_as_direct", feature_aliases_as_direct, 0, 1);
    field("max_turn_chi2", max_turn_chi2, 0, 1e6);
  }
};

// Each factor in (0, 1], piecewise linear between the knots given in docs/slam-core.md ("Quality-aware information").
double inlier_ratio_weight(double inlier_ratio);
double overlap_mse_weight(double mse_m2);
double overlap_points_weight(double points);

// The three weights' product.
double quality_weight(const PairRegistration& r);

// Information = that of a perfect registration scaled by the quality weight; on the direct path
// the horizontal and yaw entries are further scaled by direct_horizontal_share. With
// information_from_hessian, the registration's Hessian shapes it instead (observed_information),
// taken in the level frame of the target, which `level_from_target` turns the target's frame to
// (level_from_body of the target's rotation): the edge's residual is taken there.
Information6 quality_information(const PairRegistration& r, const QualityConfig& config,
                                 const Eigen::Matrix3d& level_from_target = Eigen::Matrix3d::Identity());

// Depth information no more than the relief around the answer allows (the probe's local cost as
// a variance: QualityConfig::direct_depth_from_relief), the depth row and column scaled alike so
// that the matrix stays positive semi-definite. Unchanged where the probe compared nothing.
Information6 with_depth_capped_by_relief(Information6 information, const Uniqueness& uniqueness);

}  // namespace bathyslam
