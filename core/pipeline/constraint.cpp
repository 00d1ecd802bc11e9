#include "core/pipeline/constraint.h"

#include <algorithm>
#include <stdexcept>

#include <Eigen/SVD>

namespace bathyslam {

PoseGraphEdge graph_edge(const Constraint& c) {
  return {c.from, c.to, c.measured, c.information, !from_navigation(c.type), c.anchor};
}

std::string to_string(ConstraintType t) {
  switch (t) {
    case ConstraintType::kOdometry: return "odometry";
    case ConstraintType::kAdjacent: return "adjacent";
    case ConstraintType::kLoop: return "loop";
    case ConstraintType::kDatum: return "datum";
  }
  return "?";
}

ConstraintType parse_constraint_type(const std::string& text) {
  for (ConstraintType t : {ConstraintType::kOdometry, ConstraintType::kAdjacent, ConstraintType::kLoop, ConstraintType::kDatum}) {
    if (text == to_string(t)) return t;
  }
  throw std::invalid_argument("constraint type '" + text + "' is not known to this version of the core");
}

std::string to_string(AliasResolution resolution) {
  switch (resolution) {
    case AliasResolution::kNone: return "none";
    case AliasResolution::kRuledOut: return "ruled out by dead reckoning";
    case AliasResolution::kInformationRemoved: return "information along it removed";
    case AliasResolution::kJudgedByGraph: return "judged by the graph";
  }
  return "?";
}

bool carries_horizontal_information(const Information6& information) {
  return information(0, 0) > 0 || information(1, 1) > 0 || information(5, 5) > 0;
}

Information6 without_horizontal(Information6 information) {
  for (int k : {0, 1, 5}) information.row(k).setZero(), information.col(k).setZero();
  return information;
}

Information6 widened_by_doubt(Information6 information, const OtherAnswers& others, Eigen::Matrix2d& spread) {
  spread.setZero();
  if (others.lost || others.landings.empty()) return without_horizontal(information);
  for (const Eigen::Vector2d& l : others.landings) spread += l * l.transpose() / static_cast<double>(others.landings.size());
  if (others.shifts.size() == 2) {
    // Landings ≈ A · shifts: A's singular value along a direction is the share of a start's
    // offset that GICP keeps there, 0 where it comes all the way back, 1 where it stays put.
    // Kept more than half of it, the direction is the start's, not the terrain's.
    constexpr double kKeptShare = 0.5;
    Eigen::Matrix2d shifts, landings;
    shifts << others.shifts[0], others.shifts[1];
    landings << others.landings[0], others.landings[1];
    const Eigen::JacobiSVD<Eigen::Matrix2d> svd(landings * shifts.inverse(), Eigen::ComputeFullV);
    for (int k = 0; k < 2; ++k) {
      if (svd.singularValues()(k) > kKeptShare) information = without_direction(information, svd.matrixV().col(k));
    }
  }
  return with_horizontal_spread(information, spread);
}

Information6 with_horizontal_spread(Information6 information, const Eigen::Matrix2d& spread) {
  // (C_own + S)⁻¹ written with the own block's information A, which may be singular (a direction
  // it does not observe), and S, singular along a line of competitors: (I + A S)⁻¹ A, which
  // inverts neither. (I + A S) has eigenvalues of at least 1. Written as S⁻¹ − S⁻¹ (A + S⁻¹)⁻¹ S⁻¹
  // with S regularised, it cancelled catastrophically where A is small against S's regulariser's
  // inverse: at 1500 m (A ~ 1e-5 per m²) a line of competitors oblique to the axes gave 8.8
  // per m² for 4e-5, an edge 46 m off at 23 sigma (docs/any-depth.md).
  const Eigen::Matrix2d own = information.topLeftCorner<2, 2>();
  const Eigen::Matrix2d combined = (Eigen::Matrix2d::Identity() + own * spread).partialPivLu().solve(own);
  information = without_horizontal(information);
  information.topLeftCorner<2, 2>() = 0.5 * (combined + combined.transpose());
  return information;
}

namespace {

using Direction6 = Eigen::Matrix<double, 6, 1>;

// `information` with the unit direction `u` of the residual marginalised out.
Information6 marginalised(const Information6& information, const Direction6& u) {
  const Direction6 pull = information * u;
  const double along = u.dot(pull);
  if (along <= 1e-12 * std::max(information.trace(), 1e-300)) return information;
  const Information6 marginal = information - pull * pull.transpose() / along;
  return 0.5 * (marginal + marginal.transpose());
}

}  // namespace

Information6 without_direction(const Information6& information, const Eigen::Vector2d& direction) {
  // Marginalised, not projected out: the cost minimised over an offset along the direction. A
  // projection keeps the curvature across it as if the answer were right along it; where the
  // cost's valley runs obliquely to the direction (a sand-wave train's crests under another
  // train's competitors), an answer that slid down the valley then pulls the graph across by the
  // slide's share, with the valley's steep side as its confidence (docs/slam-every-seabed.md).
  Direction6 u = Direction6::Zero();
  u.head<2>() = direction.normalized();
  return marginalised(information, u);
}

Information6 without_yaw(const Information6& information) {
  return marginalised(information, Direction6::Unit(5));
}

std::vector<Constraint> odometry_constraints(const std::vector<Eigen::Isometry3d>& dead_reckoning, const GraphConfig& graph) {
  std::vector<Constraint> constraints;
  for (const PoseGraphEdge& e : odometry_edges(dead_reckoning, Information6::Identity())) {
    if (!graph.has_step(e.from)) continue;
    Constraint c;
    c.from = e.from;
    c.to = e.to;
    c.measured = e.measured;
    c.information = odometry_information(graph, e.from);
    constraints.push_back(c);
  }
  for (int start : graph.survey_starts) {
    Constraint c;
    c.type = ConstraintType::kDatum;
    c.from = 0;
    c.to = start;
    c.measured = dead_reckoning.at(0).inverse() * dead_reckoning.at(start);
    c.information = datum_information(graph);
    constraints.push_back(c);
  }
  return constraints;
}

}  // namespace bathyslam
