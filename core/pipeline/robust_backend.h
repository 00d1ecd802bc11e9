#pragma once
// The back end's defences against wrong edges (issue 14): which registrations the graph may
// believe (the safety net that checks the solution before it is published: safety_net.h).
#include <functional>
#include <limits>
#include <vector>

#include "core/graph/dr_noise.h"
#include "core/graph/loop_consistency.h"
#include "core/pipeline/constraint.h"
#include "core/pipeline/pipeline_config.h"

namespace bathyslam {

// The DR gate: could dead reckoning have drifted to this registration's answer? Sets the
// constraint's statistic, and refuses it when not.
void gate_against_dead_reckoning(Constraint& c, const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses,
                                 const PlausibilityConfig& config);

// A direct answer's turn is not in its information, so the DR gate cannot refuse it; where GICP
// turned the overlap against dead reckoning's heading by more than the heading noise between the
// two submaps allows (squared turn over DR's yaw variance above `max_turn_chi2`; 0: not tested),
// its position was found together with a wrong turn: it keeps depth, roll and pitch only.
void drop_position_if_turned(Constraint& c, const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses,
                             double max_turn_chi2);

// Dead reckoning's horizontal standard deviation between two submaps along its worst direction:
// how far from the truth a guess it gives may be.
double dr_horizontal_sigma(const DrNoiseModel& dr, int from, int to);

// What resolve_alias does with an answer some plausible competitor contends with (QualityConfig's
// doubt_widens, widen_min_distinctness, feature_aliases_as_direct, direct_depth_from_relief);
// all off, the rule as it first was.
struct AliasRule {
  bool widens = false;                  // widened along the plausible competitors, not stripped
  double widen_min_distinctness = 0;    // ... unless another basin fits nearly as well
  bool feature_aided_as_direct = false;  // a feature-aided answer judged as a direct one, not refused
  bool depth_from_relief = false;       // ... its depth then capped as a direct answer's is
  // The best other basin takes the horizontal information only if the gate allows it.
  bool distinctness_among_plausible = false;
};
AliasRule alias_rule(const QualityConfig& quality);

// The squared Mahalanobis distance of a registration's answer moved by `along` (m, in its
// target's level frame) from a prediction of it.
using AliasGate = std::function<double(const Eigen::Vector2d& along)>;

// The uniqueness test with dead reckoning's word (robustness.alias_from_prior), for an accepted
// registration with its information. A feature-aided answer at least `min_distinctness` distinct
// stands, as in issue 14. Otherwise other offsets whose terrain fits nearly as well as the
// answer's (the probe's competitors) do not refuse the answer when each of them fails the DR gate:
// dead reckoning has chosen between them. When some do not, a direct answer keeps no horizontal
// information, or with `rule.widens` has the scatter of those it allows added to its covariance,
// unless the best other local minimum in the probe fits nearly as well as the answer
// (distinctness under `rule.widen_min_distinctness`); a feature-aided one is refused, or with
// `rule.feature_aided_as_direct` judged as a direct one would be (its turn marginalised out, its
// depth capped by the relief). One whose overlap was too small to probe is refused either way.
// `level_from_target` turns the target submap's frame, where the offsets lie, into the edge's
// residual frame.
void resolve_alias(Constraint& c, const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses,
                   double min_distinctness, const PlausibilityConfig& config, const Eigen::Matrix3d& level_from_target,
                   const AliasRule& rule = {});

// The same under any gate: `gate_at` judges each competitor in place of dead reckoning.
void resolve_alias(Constraint& c, const AliasGate& gate_at, double min_distinctness, const PlausibilityConfig& config,
                   const Eigen::Matrix3d& level_from_target, const AliasRule& rule = {});

// Dead reckoning's gate for resolve_alias: the DR gate's statistic (x, y, yaw; DR's covariance
// between the submaps and the registration's own) for the answer moved by an offset.
AliasGate dr_alias_gate(const Constraint& c, const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses);

// The graph's gate (robustness.alias_from_graph): the answer against the graph's estimate of the
// pair, x and y only, under `covariance` (the graph's, relative_covariances) and half the probe's
// step for where the answer lies within its own basin. The registration's own information is left
// out: it is shaped by the quality weight, not by the width of the answer's basin, and on sand
// waves its sigmas of metres made every trough a crest away look plausible
// (docs/slam-every-seabed.md).
AliasGate graph_alias_gate(const Constraint& c, const std::vector<Eigen::Isometry3d>& estimate,
                           const Eigen::Matrix2d& covariance);

// The rotation from `c`'s target submap frame, where the probe's offsets lie, into its edge's
// residual frame (the target's level frame), the target at `poses[c.from]`.
Eigen::Matrix3d level_from_target_of(const Constraint& c, const std::vector<Eigen::Isometry3d>& poses);

// Whether `rejection` rests on dead reckoning's noise model (the DR gate, or with
// plan.alias_from_prior the uniqueness test), so that a better model may take it back.
bool refused_by_prior(const Rejection& rejection, const Plan& plan);

// Everything about a registration that rests on dead reckoning's noise model, decided anew:
// the alias rule (plan.alias_from_prior) under `aliases` and the DR gate (plan.dr_gate) under
// `dr`, from the registration's own verdict and information. A registration these refused before
// is tested again, so a registration judged under one noise model can be judged under a better
// one. The survey's estimate gives two (navigation_noise.h): the loosest heading it does not
// rule out for the gate, for the aliases the likeliest where the data determine it (alias_graph).
// With `graph_gate`, where dead reckoning leaves competitors open the graph's gate judges them
// again and its verdict is kept for every later judgement (robustness.alias_from_graph).
void judge_with_prior(Constraint& c, const DrNoiseModel& dr, const DrNoiseModel& aliases,
                      const std::vector<Eigen::Isometry3d>& dr_poses, const PipelineConfig& config, const Plan& plan,
                      const AliasGate* graph_gate = nullptr);

// Pairwise consistency (PCM) over the accepted registrations that carry horizontal information
// (the ones that can bend the survey); the rest of the accepted set is left out of the graph
// with the reason. Selected again from all of them on each call: a later batch may confirm a
// registration an earlier one could not. With `known`, kept from one call to the next for the
// same growing `constraints`, each pair's test is computed once.
void select_consistent_registrations(std::vector<Constraint>& constraints, const DrNoiseModel& dr,
                                     const std::vector<Eigen::Isometry3d>& dr_poses, const LoopConsistencyConfig& config,
                                     KnownConflicts* known = nullptr);

// The graph of the constraints in it, solved from `initial` (dead reckoning, or a batch's
// estimate). With `nodes`, only the constraints among the first `nodes` poses; the others keep
// `initial`. With `first_free`, the poses before it are held at `initial` too.
GraphSolution solve(const std::vector<Eigen::Isometry3d>& initial, const std::vector<Constraint>& constraints,
                    const GraphConfig& config, int nodes = std::numeric_limits<int>::max(), int first_free = 1);

}  // namespace bathyslam
