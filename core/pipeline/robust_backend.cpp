#include "core/pipeline/robust_backend.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "core/types/format.h"

namespace bathyslam {
namespace {

PoseGraphEdge edge_of(const Constraint& c) {
  return {c.from, c.to, c.measured, c.information, !from_navigation(c.type), c.anchor};
}

// How hard an edge pulls against a solution, in sigmas of its own information on x, y and yaw.
double horizontal_pull_sigma(const PoseGraphEdge& edge, const std::vector<Eigen::Isometry3d>& poses) {
  const Eigen::Matrix<double, 6, 1> error = edge_error(edge, poses[edge.from], poses[edge.to]);
  const Eigen::Vector3d e(error(0), error(1), error(5));
  return std::sqrt(std::max(0.0, e.dot(xy_yaw_block(edge.information) * e)));
}

// No registration enters the published map: each says so, so that the report's accepted edges
// are those the map was made with.
void publish_dead_reckoning(PipelineResult& r) {
  r.graph.poses = r.dr_poses;
  r.optimized_poses = r.dr_poses;
  for (Constraint& c : r.constraints) {
    if (!from_navigation(c.type) && c.in_graph()) c.exclusion = {RejectionKind::kSafetyNet, "dead reckoning published instead"};
  }
}

std::string describe(const Constraint& c) {
  return to_string(c.type) + " " + std::to_string(c.from) + "->" + std::to_string(c.to) + " (" + (c.path ? to_string(*c.path) : "odometry") + ")";
}

// RMS distance from the answer along and across the main line of a scatter Σ o oᵀ / n.
Eigen::Vector2d spread_of(const Eigen::Matrix2d& scatter) {
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(scatter).eigenvalues().cwiseMax(0.0).cwiseSqrt().reverse();
}

}  // namespace

void gate_against_dead_reckoning(Constraint& c, const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses,
                                 const PlausibilityConfig& config) {
  if (!c.accepted()) return;
  const DrInnovation innovation = dr_innovation(edge_of(c), dr, dr_poses);
  c.dr_mahalanobis2 = mahalanobis2_xy_yaw(innovation.difference, dr.covariance(c.from, c.to) + innovation.measurement);
  if (c.dr_mahalanobis2 <= config.chi2_threshold) return;
  c.rejection = {RejectionKind::kImplausible, format("Mahalanobis2 %.1f > %.1f over %.0f submaps", c.dr_mahalanobis2,
                                                      config.chi2_threshold, static_cast<double>(std::abs(c.to - c.from)))};
}

double dr_horizontal_sigma(const DrNoiseModel& dr, int from, int to) {
  const Eigen::Matrix2d horizontal = dr.covariance(from, to).topLeftCorner<2, 2>();
  return std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(horizontal).eigenvalues().maxCoeff()));
}

void resolve_alias(Constraint& c, const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses,
                   double min_distinctness, const PlausibilityConfig& config, const Eigen::Matrix3d& level_from_target,
                   bool widens, double widen_min_distinctness) {
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

  // The DR gate's statistic for the answer moved by each competitor's offset: the difference
  // from dead reckoning moves by the offset (in `from`'s level frame), its covariance stays.
  const DrInnovation innovation = dr_innovation(edge_of(c), dr, dr_poses);
  const Vector6& difference = innovation.difference;
  const Eigen::LDLT<Eigen::Matrix3d> gate(xy_yaw_block(dr.covariance(c.from, c.to) + innovation.measurement));
  Eigen::Matrix2d plausible_spread = Eigen::Matrix2d::Zero();  // of the plausible offsets
  int plausible = 0;
  double nearest = std::numeric_limits<double>::infinity();
  const auto gate_at = [&](const Eigen::Vector2d& along) {
    const Eigen::Vector3d d(difference(0) + along.x(), difference(1) + along.y(), difference(5));
    return d.dot(gate.solve(d));
  };
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
  if (feature_aided) {
    c.rejection = {RejectionKind::kNotUnique,
                   format("%.0f other offsets fit nearly as well as the answer and dead reckoning allows %.0f of them "
                          "(nearest Mahalanobis2 %.1f)",
                          static_cast<double>(competitors.size()), static_cast<double>(plausible), nearest)};
    return;
  }
  // A direct answer where an alias is plausible: with quality.doubt_widens, anywhere among the
  // plausible competitors (their scatter added to its covariance: along a line of them, such as
  // sand-wave crests, it keeps the position across the line only as well as the line is narrow);
  // without, no horizontal information at all. Keeping the position across the line with the
  // answer's own information was tried: on `small` sand waves and on `lake` such edges sat
  // 7-17 sigma off across the line, the truth not among the probe's competitors.
  c.alias_spread_m = spread_of(plausible_spread / plausible);
  c.alias = AliasResolution::kInformationRemoved;
  if (!widens || !carries_horizontal_information(c.information) || u.distinctness() < widen_min_distinctness) {
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

bool refused_by_prior(const Rejection& rejection, const Plan& plan) {
  return rejection.kind == RejectionKind::kImplausible ||
         (plan.alias_from_prior && rejection.kind == RejectionKind::kNotUnique);
}

void judge_with_prior(Constraint& c, const DrNoiseModel& dr, const std::vector<Eigen::Isometry3d>& dr_poses,
                      const PipelineConfig& config, const Plan& plan) {
  if (from_navigation(c.type)) return;
  // With the alias rule on, acceptance leaves the uniqueness test to resolve_alias: every
  // kNotUnique is the prior's, as every kImplausible is.
  if (refused_by_prior(c.rejection, plan)) c.rejection = {};
  if (!c.accepted()) return;
  if (plan.quality_aware) c.information = c.registered_information;
  c.alias = AliasResolution::kNone;
  c.alias_mahalanobis2 = -1;
  if (plan.alias_from_prior) {
    const Eigen::Matrix3d level_from_target =
        level_from_body(Eigen::Quaterniond(dr_poses[c.from].rotation())).toRotationMatrix();
    resolve_alias(c, dr, dr_poses, config.acceptance.min_distinctness, config.robustness.pcm.plausibility,
                  level_from_target, config.quality.doubt_widens, config.quality.widen_min_distinctness);
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
    candidates.push_back(loop_candidate(edge_of(c), dr_poses));
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
      edges.push_back(edge_of(c));
    }
  }
  return optimize_pose_graph(initial, edges, config, first_free);
}

void solve_with_safety_net(PipelineResult& r, const PipelineConfig& config) {
  SafetyNet& net = r.safety_net;
  net = SafetyNet{};
  net.ran = true;
  std::vector<int> line_of_node;
  for (const Submap& s : r.submaps.submaps) line_of_node.push_back(s.line);
  const auto& robustness = config.robustness;
  for (int round = 0;; ++round) {
    std::vector<PoseGraphEdge> edges;
    std::vector<std::size_t> owner;
    for (std::size_t k = 0; k < r.constraints.size(); ++k) {
      if (!r.constraints[k].in_graph()) continue;
      edges.push_back(edge_of(r.constraints[k]));
      owner.push_back(k);
    }
    r.graph = optimize_pose_graph(r.dr_poses, edges, r.navigation_noise.graph);
    net.check = check_graph(r.graph.poses, edges, line_of_node, robustness.line_check);
    int hardest = -1;
    double hardest_sigma = 0;
    for (std::size_t e = 0; e < edges.size(); ++e) {
      if (!edges[e].robust) continue;
      const double sigma = horizontal_pull_sigma(edges[e], r.graph.poses);
      if (sigma > hardest_sigma) hardest_sigma = sigma, hardest = static_cast<int>(e);
    }
    const bool pulls = hardest_sigma > robustness.max_pull_sigma;
    if (net.check.pass && !pulls) {
      net.verdict = net.dropped.empty()
                        ? "pass: every line within dead reckoning's noise, no registration pulling beyond " +
                              format("%.0f sigma", robustness.max_pull_sigma)
                        : format("pass after dropping %.0f registrations", static_cast<double>(net.dropped.size()));
      return;
    }
    if (hardest < 0 || round >= robustness.max_drops) {
      net.pass = false;
      net.fell_back = true;
      net.verdict = format("FAILED after dropping %.0f registrations (%s): published dead reckoning instead",
                           static_cast<double>(net.dropped.size()),
                           net.check.pass ? "registrations still pulling against the solution" : "lines bent beyond their noise");
      publish_dead_reckoning(r);
      return;
    }
    Constraint& worst = r.constraints[owner[hardest]];
    worst.exclusion = {RejectionKind::kSafetyNet, format("pulled %.1f sigma against the solution", hardest_sigma) +
                                                      (net.check.pass ? "" : ", lines bent beyond their noise")};
    net.dropped.push_back(describe(worst) + ": " + worst.exclusion.text());
  }
}

namespace {

// How high dead reckoning's p99 could be by the sampling of its cells alone (publish_rule).
// The block bootstrap re-reads the map, so it runs only where the cheaper bound would refuse.
double dr_p99_bound(const PipelineResult& r, double solved_p99) {
  const ConsistencyReport& dr = r.dr_consistency;
  const int rule = r.config.robustness.publish_rule;
  if (rule == 0) return dr.stats.p99;
  const double cells = std::max(dr.stats.p99, dr.p99_upper);
  if (rule == 1 || solved_p99 <= cells) return cells;
  const double block_m = median_submap_side_m(r.submaps);
  if (block_m <= 0) return cells;
  return std::max(cells, p99_upper_by_blocks(r.submaps, r.dr_poses, r.config.consistency, block_m));
}

}  // namespace

void fall_back_unless_more_consistent(PipelineResult& r) {
  const ErrorStats &solved = r.consistency.stats, &dr = r.dr_consistency.stats;
  const bool whole_map = r.config.robustness.publish_rule >= 1;
  const bool rmse_no_higher = solved.rmse <= dr.rmse;
  const double p99_bound = rmse_no_higher ? dr_p99_bound(r, solved.p99) : dr.p99;
  if (rmse_no_higher && solved.p99 <= p99_bound) return;
  r.safety_net.pass = false;
  r.safety_net.fell_back = true;
  r.safety_net.verdict = format("FAILED: the solved map agrees with itself less than dead reckoning's (consistency RMSE %.3f m "
                                "against %.3f m, p99 %.3f m against %.3f m%s): published dead reckoning instead",
                                solved.rmse, dr.rmse, solved.p99, dr.p99,
                                whole_map && rmse_no_higher
                                    ? format(", at most %.3f m within its sampling noise", p99_bound).c_str()
                                    : "");
  publish_dead_reckoning(r);
  r.consistency = r.dr_consistency;
}

}  // namespace bathyslam
