#pragma once
// graph_check: the per-job safety net after a solve. Along a survey line DR is good and a correct
// graph bends it only within its noise; a wrong loop forced in bends the lines it joins far
// beyond. Per line, the odometry residuals of the solution are tested against a chi-square
// quantile, and every registration edge's pull is measured, so a caller can say which lines
// failed and which edges pulled hardest.
#include <vector>

#include <Eigen/Geometry>

#include "core/graph/pose_graph.h"

namespace bathyslam {

// The standard normal's quantile (Acklam's rational approximation, relative error < 1.2e-9).
double normal_quantile(double p);

// The chi-square quantile at `p` for `dof` degrees of freedom, by the Wilson–Hilferty cube-root
// normal approximation: within 2 % at 3 dof and 99.9 %, closer as dof grow (a line has dozens).
double chi_square_quantile(double p, double dof);

// A line: a run of consecutive nodes sharing a line id (≥ 0), nodes first..last.
struct LineRun {
  int line = -1;
  int first = 0;
  int last = 0;
};

// The runs of `line_of_node` (−1: a turn or transit, in no line). An id that comes back after a
// break makes a second run.
std::vector<LineRun> line_runs(const std::vector<int>& line_of_node);

struct GraphCheckConfig {
  // A correct line fails one job in a thousand. Odometry residuals of a solved graph are smaller
  // than DR's noise (the solve fits them), so correct lines sit far below the quantile and a
  // wrong loop's bend stands out even at this level.
  double p = 0.999;
  template <typename Field>
  void fields(Field&& field) {
    field("p", p, 0.5, 0.999999);
  }
};

struct LineCheck {
  LineRun run;
  int edges = 0;       // odometry edges inside the run
  double chi2 = 0;     // Σ rᵀΣ⁻¹r over them, r their error's x, y and yaw
  int dof = 0;         // 3 per edge
  double threshold = 0;  // chi_square_quantile(p, dof)
  bool pass = true;
  double chi2_per_dof() const { return dof > 0 ? chi2 / dof : 0.0; }
};

struct EdgePull {
  int edge = 0;              // index into the edges checked
  double whitened_norm = 0;  // |whitened_residual| at the solution
};

struct GraphCheck {
  bool pass = true;
  std::vector<LineCheck> lines;        // in survey order
  std::vector<int> worst_lines;        // indices into `lines` of those that fail, χ²/threshold descending
  std::vector<EdgePull> registration_pulls;  // every robust edge, hardest pull first
};

// Checks `poses` (a solution) against `edges` (all of them: odometry edges are the non-robust
// ones joining consecutive nodes). Only x, y and yaw of the odometry residuals count: they are
// what a wrong registration bends and what DR's noise model is loose on, while depth is what the
// sonar legitimately corrects, so a depth residual is no failure; roll and pitch stay put.
GraphCheck check_graph(const std::vector<Eigen::Isometry3d>& poses, const std::vector<PoseGraphEdge>& edges,
                       const std::vector<int>& line_of_node, const GraphCheckConfig& config = {});

}  // namespace bathyslam
