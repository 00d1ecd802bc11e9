#include "core/pipeline/robust_backend.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "core/types/format.h"

namespace bathyslam {
namespace {

// RMS distance from the answer along and across the main line of a scatter Σ o oᵀ / n.
Eigen::Vector2d spread_of(const Eigen::Matrix2d& scatter) {
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(scatter).eigenvalues().cwiseMax(0.0).cwiseSqrt().reverse();
}

}  // namespace

void gate_against_dead_reckoning(Constraint& c, const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses,
                                 const PlausibilityConfig& config) {
  if (!c.accepted()) return;
  const DrInnovation innovation = dr_innovation(graph_edge(c), dr, dr_poses);
  c.dr_mahalanobis2 = mahalanobis2_xy_yaw(innovation.difference, dr.covariance(c.from, c.to) + innovation.measurement);
  if (c.dr_mahalanobis2 <= config.chi2_threshold) return;
  c.rejection = {RejectionKind::kImplausible, format("Mahalanobis2 %.1f > %.1f over %.0f submaps", c.dr_mahalanobis2,
                                                      config.chi2_threshold, static_cast<double>(std::abs(c.to - c.from)))};
}

void drop_position_if_turned(Constraint& c, const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses,
                             double max_turn_chi2) {
  if (max_turn_chi2 <= 0 || c.path != RegistrationPath::kDirect || !carries_horizontal_information(c.information)) return;
  const double turn = dr_innovation(graph_edge(c), dr, dr_poses).difference(5);
  if (turn * turn > max_turn_chi2 * dr.covariance(c.from, c.to)(5, 5)) c.information = without_horizontal(c.information);
}

AliasRule alias_rule(const QualityConfig& quality) {
  return {quality.doubt_widens, quality.widen_min_distinctness, quality.feature_aliases_as_direct,
          quality.direct_depth_from_relief};
}

double dr_horizontal_sigma(const DrNoiseModel& dr, int from, int to) {
  const Eigen::Matrix2d horizontal = dr.covariance(from, to).topLeftCorner<2, 2>();
  return std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(horizontal).eigenvalues().maxCoeff()));
}

AliasGate dr_alias_gate(const Constraint& c, const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses) {
  // The DR gate's statistic for the answer moved by an offset: the difference from dead reckoning
  // moves by the offset (in `from`'s level frame), its covariance stays.
  const DrInnovation innovation = dr_innovation(graph_edge(c), dr, dr_poses);
  const Vector6 difference = innovation.difference;
  const Eigen::LDLT<Eigen::Matrix3d> gate(xy_yaw_block(dr.covariance(c.from, c.to) + innovation.measurement));
  return [difference, gate](const Eigen::Vector2d& along) {
    const Eigen::Vector3d d(difference(0) + along.x(), difference(1) + along.y(), difference(5));
    return d.dot(gate.solve(d));
  };
}

AliasGate graph_alias_gate(const Constraint& c, const std::vector<Eigen::Isometry3d>& estimate,
                           const Eigen::Matrix2d& covariance) {
  const Eigen::Isometry3d predicted = level_frame(estimate[c.from]).inverse() * level_frame(estimate[c.to]);
  const Eigen::Vector2d difference =
      pose_difference(between_level_frames(c.measured, estimate[c.from], estimate[c.to]), predicted).head<2>();
  const double half_step = c.uniqueness.step_m / 2;
  const Eigen::LDLT<Eigen::Matrix2d> gate(covariance + half_step * half_step * Eigen::Matrix2d::Identity());
  return [difference, gate](const Eigen::Vector2d& along) {
    const Eigen::Vector2d d = difference + along;
    return d.dot(gate.solve(d));
  };
}

namespace {

// resolve_alias, the gate made only once there are competitors to judge: most answers have none,
// and dead reckoning's gate costs the measurement's covariance (an eigen-decomposition) each time
// every registration is judged again.
void resolve_alias_gated(Constraint& c, const std::function<AliasGate()>& make_gate, double min_distinctness,
                         const PlausibilityConfig& config, const Eigen::Matrix3d& level_from_target, const AliasRule& rule) {
  if (!c.accepted()) return;
  const bool feature_aided = c.path == RegistrationPath::kFeatureAided;
  const Uniqueness& u = c.uniqueness;
  if (!u.probed) {
    // Nothing says the answer is the terrain's: a feature-aided one is refused, a direct one keeps
    // depth, roll and pitch.
    if (feature_aided) {
      c.rejection = {RejectionKind::kNotUnique, "too little terrain overlap to probe its uniqueness"};
    } else {
      c.information = without_horizontal(c.information);
      c.alias = AliasResolution::kInformationRemoved;
    }
    return;
  }
  // A feature-aided answer as distinct as issue 14 asks stands (its features chose it, and the
  // shoulders of its basin are no alternative); a direct one must have no competitor at all.
  if (feature_aided && u.distinctness() >= min_distinctness) return;
  const std::vector<Eigen::Vector2d> competitors = u.competitor_offsets();
  if (competitors.empty()) return;

  const AliasGate gate_at = make_gate();
  Eigen::Matrix2d plausible_spread = Eigen::Matrix2d::Zero();  // of the plausible offsets
  int plausible = 0;
  double nearest = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& offset : competitors) {
    const Eigen::Vector2d along = level_offset(level_from_target, offset);
    const double m2 = gate_at(along);
    nearest = std::min(nearest, m2);
    if (m2 > config.chi2_threshold) continue;
    ++plausible;
    plausible_spread += along * along.transpose();
  }
  c.alias_mahalanobis2 = nearest;
  if (plausible == 0) {
    c.alias = AliasResolution::kRuledOut;
    return;
  }
  if (feature_aided && !rule.feature_aided_as_direct) {
    c.rejection = {RejectionKind::kNotUnique,
                   format("%.0f other offsets fit nearly as well as the answer and dead reckoning allows %.0f of them "
                          "(nearest Mahalanobis2 %.1f)",
                          static_cast<double>(competitors.size()), static_cast<double>(plausible), nearest)};
    return;
  }
  // A direct answer where an alias is plausible (or a feature-aided one, judged as one: its
  // features chose among the competitors, but what it keeps must hold at any of them, so no turn
  // and no more depth than the relief allows): with quality.doubt_widens, anywhere among the
  // plausible competitors (their scatter added to its covariance: along a line of them, such as
  // sand-wave crests, it keeps the position across the line only as well as the line is narrow);
  // without, no horizontal information at all. Keeping the position across the line with the
  // answer's own information was tried: on `small` sand waves and on `lake` such edges sat
  // 7-17 sigma off across the line, the truth not among the probe's competitors.
  c.alias_spread_m = spread_of(plausible_spread / plausible);
  c.alias = AliasResolution::kInformationRemoved;
  if (feature_aided) {
    c.information = without_yaw(c.information);
    if (rule.depth_from_relief) c.information = with_depth_capped_by_relief(c.information, u);
  }
  // Another basin fitting nearly as well leaves nothing horizontal, unless the prediction rules
  // that basin out (rule.distinctness_among_plausible).
  const bool contested = u.distinctness() < rule.widen_min_distinctness &&
                         (!rule.distinctness_among_plausible ||
                          gate_at(level_offset(level_from_target, u.alternative_offset_m)) <= config.chi2_threshold);
  if (!rule.widens || !carries_horizontal_information(c.information) || contested) {
    c.information = without_horizontal(c.information);
    return;
  }
  // Along a direction where plausible competitors go on past what the probe compared (a crest,
  // a flat, a strip of overlap) their scatter measures the probe, not the alias: nothing is
  // known there.
  std::vector<Eigen::Vector2d> open;
  for (const Eigen::Vector2d& offset : u.competitor_offsets(true)) {
    const Eigen::Vector2d along = level_offset(level_from_target, offset);
    if (gate_at(along) <= config.chi2_threshold) open.push_back(along);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> axes(plausible_spread);
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector2d axis = axes.eigenvectors().col(k), across(-axis.y(), axis.x());
    const bool runs_on = std::any_of(open.begin(), open.end(), [&](const Eigen::Vector2d& o) {
      return std::abs(o.dot(axis)) >= std::abs(o.dot(across));
    });
    if (runs_on) c.information = without_direction(c.information, axis);
  }
  c.information = with_horizontal_spread(c.information, plausible_spread / plausible);
}

}  // namespace

void resolve_alias(Constraint& c, const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses,
                   double min_distinctness, const PlausibilityConfig& config, const Eigen::Matrix3d& level_from_target,
                   const AliasRule& rule) {
  resolve_alias_gated(c, [&] { return dr_alias_gate(c, dr, dr_poses); }, min_distinctness, config, level_from_target, rule);
}

void resolve_alias(Constraint& c, const AliasGate& gate_at, double min_distinctness, const PlausibilityConfig& config,
                   const Eigen::Matrix3d& level_from_target, const AliasRule& rule) {
  resolve_alias_gated(c, [&] { return gate_at; }, min_distinctness, config, level_from_target, rule);
}

Eigen::Matrix3d level_from_target_of(const Constraint& c, const std::vector<Eigen::Isometry3d>& poses) {
  return level_from_body(Eigen::Quaterniond(poses[c.from].rotation())).toRotationMatrix();
}

bool refused_by_prior(const Rejection& rejection, const Plan& plan) {
  return rejection.kind == RejectionKind::kImplausible ||
         (plan.alias_from_prior && rejection.kind == RejectionKind::kNotUnique);
}

void judge_with_prior(Constraint& c, const DrNoiseModel& dr, const DrNoiseModel& aliases,
                      const std::vector<Eigen::Isometry3d>& dr_poses, const PipelineConfig& config, const Plan& plan,
                      const AliasGate* graph_gate) {
  if (from_navigation(c.type)) return;
  // With the alias rule on, acceptance leaves the uniqueness test to resolve_alias: every
  // kNotUnique is the prior's, as every kImplausible is.
  if (refused_by_prior(c.rejection, plan)) c.rejection = {};
  if (!c.accepted()) return;
  if (plan.quality_aware) c.information = c.registered_information;
  c.alias = AliasResolution::kNone;
  c.alias_mahalanobis2 = -1;
  c.alias_spread_m.setZero();
  if (plan.quality_aware && plan.dr_gate) drop_position_if_turned(c, dr, dr_poses, config.quality.max_turn_chi2);
  if (plan.alias_from_prior) {
    const Information6 unjudged = c.information;
    const Eigen::Matrix3d level_from_target = level_from_target_of(c, dr_poses);
    const AliasRule rule = alias_rule(config.quality);
    resolve_alias(c, aliases, dr_poses, config.acceptance.min_distinctness, config.robustness.pcm.plausibility,
                  level_from_target, rule);
    if (c.alias == AliasResolution::kInformationRemoved && c.accepted()) {
      // Where dead reckoning leaves competitors open, the graph kept before the registration may
      // not (robustness.alias_from_graph): its verdict, now or as given before, stands. An answer
      // the graph itself does not allow (GICP slid along a crest from a good guess) gets none.
      const double threshold = config.robustness.pcm.plausibility.chi2_threshold;
      if (graph_gate && (*graph_gate)(Eigen::Vector2d::Zero()) <= threshold) {
        const double dr_nearest = c.alias_mahalanobis2;
        c.information = unjudged;
        AliasRule among_plausible = rule;
        among_plausible.distinctness_among_plausible = true;
        resolve_alias(c, *graph_gate, config.acceptance.min_distinctness, config.robustness.pcm.plausibility,
                      level_from_target, among_plausible);
        // The graph picks the basin, not the place in it: no better than the probe's step (an
        // answer GICP did not come back to from other starts was kept 1.0 m off at 6 sigma).
        const double step = c.uniqueness.step_m;
        c.information = with_horizontal_spread(c.information, step * step * Eigen::Matrix2d::Identity());
        c.alias_mahalanobis2 = dr_nearest;
        c.graph_information = c.accepted() ? std::optional<Information6>(c.information) : std::nullopt;
      }
      if (c.graph_information && c.accepted()) {
        c.information = *c.graph_information;
        c.alias = AliasResolution::kJudgedByGraph;
      }
    }
  }
  if (plan.dr_gate) gate_against_dead_reckoning(c, dr, dr_poses, config.robustness.pcm.plausibility);
}

void select_consistent_registrations(std::vector<Constraint>& constraints, const DrNoiseModel& dr,
                                     const std::vector<Eigen::Isometry3d>& dr_poses, const LoopConsistencyConfig& config,
                                     KnownConflicts* known) {
  std::vector<std::size_t> owner;
  std::vector<LoopCandidate> candidates;
  for (std::size_t k = 0; k < constraints.size(); ++k) {
    Constraint& c = constraints[k];
    if (from_navigation(c.type)) continue;
    if (c.exclusion.kind == RejectionKind::kInconsistent) c.exclusion = {};
    if (!c.in_graph() || !carries_horizontal_information(c.information)) continue;
    owner.push_back(k);
    candidates.push_back(loop_candidate(graph_edge(c), dr_poses));
    candidates.back().id = static_cast<int>(k);
  }
  const LoopSelection selection = select_consistent_loops(candidates, dr, config, known);
  for (std::size_t i = 0; i < owner.size(); ++i) {
    if (selection.verdicts[i] == LoopVerdict::kept) continue;
    constraints[owner[i]].exclusion = {RejectionKind::kInconsistent, selection.verdicts[i] == LoopVerdict::implausible
                                                                         ? "implausible against dead reckoning"
                                                                         : "not in the largest consistent set"};
  }
}

GraphSolution solve(const std::vector<Eigen::Isometry3d>& initial, const std::vector<Constraint>& constraints,
                    const GraphConfig& config, int nodes, int first_free) {
  std::vector<PoseGraphEdge> edges;
  for (const Constraint& c : constraints) {
    // An edge between two held nodes adds a constant to the cost.
    if (c.in_graph() && c.from < nodes && c.to < nodes && std::max(c.from, c.to) >= first_free) {
      edges.push_back(graph_edge(c));
    }
  }
  return optimize_pose_graph(initial, edges, config, first_free);
}

}  // namespace bathyslam
