#include "core/pipeline/constraint.h"

#include <stdexcept>

namespace bathyslam {

std::string to_string(ConstraintType t) {
  switch (t) {
    case ConstraintType::kOdometry: return "odometry";
    case ConstraintType::kAdjacent: return "adjacent";
    case ConstraintType::kLoop: return "loop";
  }
  return "?";
}

ConstraintType parse_constraint_type(const std::string& text) {
  for (ConstraintType t : {ConstraintType::kOdometry, ConstraintType::kAdjacent, ConstraintType::kLoop}) {
    if (text == to_string(t)) return t;
  }
  throw std::invalid_argument("constraint type '" + text + "' is not known to this version of the core");
}

std::string to_string(AliasResolution resolution) {
  switch (resolution) {
    case AliasResolution::kNone: return "none";
    case AliasResolution::kRuledOut: return "ruled out by dead reckoning";
    case AliasResolution::kInformationRemoved: return "information along it removed";
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

std::vector<Constraint> odometry_constraints(const std::vector<Eigen::Isometry3d>& dead_reckoning, const GraphConfig& graph) {
  const Information6 dr_information = information_from_sigmas(graph.dr_sigma_translation_m, graph.dr_sigma_rotation_rad);
  std::vector<Constraint> constraints;
  for (const PoseGraphEdge& e : odometry_edges(dead_reckoning, dr_information)) {
    Constraint c;
    c.from = e.from;
    c.to = e.to;
    c.measured = e.measured;
    c.information = e.information;
    constraints.push_back(c);
  }
  return constraints;
}

}  // namespace bathyslam
