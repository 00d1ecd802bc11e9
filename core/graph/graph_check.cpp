#include "core/graph/graph_check.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/graph/dr_noise.h"

namespace bathyslam {
namespace {

bool is_odometry(const PoseGraphEdge& edge) { return !edge.robust && std::abs(edge.to - edge.from) == 1; }

bool inside(const LineRun& run, int node) { return node >= run.first && node <= run.last; }

LineCheck check_line(const LineRun& run, const std::vector<Eigen::Isometry3d>& poses,
                     const std::vector<PoseGraphEdge>& edges, double p) {
  LineCheck check;
  check.run = run;
  for (const PoseGraphEdge& edge : edges) {
    if (!is_odometry(edge) || !inside(run, edge.from) || !inside(run, edge.to)) continue;
    const Vector6 error = edge_error(edge, poses.at(edge.from), poses.at(edge.to));
    check.chi2 += mahalanobis2_xy_yaw(error, covariance_from_information(edge.information));
    ++check.edges;
  }
  check.dof = 3 * check.edges;
  check.threshold = check.dof > 0 ? chi_square_quantile(p, check.dof) : 0.0;
  check.pass = check.chi2 <= check.threshold;
  return check;
}

}  // namespace

// Acklam's algorithm: a rational function in the centre, another in √(−2 ln p) in the tails.
double normal_quantile(double p) {
  if (!(p > 0 && p < 1)) throw std::invalid_argument("normal_quantile: p must lie in (0, 1)");
  static constexpr double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                                 1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static constexpr double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                                 6.680131188771972e+01,  -1.328068155288572e+01};
  static constexpr double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                                 -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static constexpr double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                                 3.754408661907416e+00};
  constexpr double p_low = 0.02425;
  auto tail = [&](double q) {
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  };
  if (p < p_low) return tail(std::sqrt(-2 * std::log(p)));
  if (p > 1 - p_low) return -tail(std::sqrt(-2 * std::log(1 - p)));
  const double q = p - 0.5, r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

// (χ²/k)^(1/3) is close to normal with mean 1 − 2/(9k) and variance 2/(9k).
double chi_square_quantile(double p, double dof) {
  if (!(dof > 0)) throw std::invalid_argument("chi_square_quantile: dof must be positive");
  const double h = 2.0 / (9.0 * dof);
  const double cube_root = 1.0 - h + normal_quantile(p) * std::sqrt(h);
  return dof * std::pow(std::max(cube_root, 0.0), 3);
}

std::vector<LineRun> line_runs(const std::vector<int>& line_of_node) {
  std::vector<LineRun> runs;
  for (int i = 0; i < static_cast<int>(line_of_node.size()); ++i) {
    const int line = line_of_node[i];
    if (line < 0) continue;
    if (!runs.empty() && runs.back().line == line && runs.back().last == i - 1) {
      runs.back().last = i;
    } else {
      runs.push_back({line, i, i});
    }
  }
  return runs;
}

GraphCheck check_graph(const std::vector<Eigen::Isometry3d>& poses, const std::vector<PoseGraphEdge>& edges,
                       const std::vector<int>& line_of_node, const GraphCheckConfig& config) {
  GraphCheck result;
  for (const LineRun& run : line_runs(line_of_node)) {
    result.lines.push_back(check_line(run, poses, edges, config.p));
    if (!result.lines.back().pass) {
      result.pass = false;
      result.worst_lines.push_back(static_cast<int>(result.lines.size()) - 1);
    }
  }
  auto excess = [&](int k) { return result.lines[k].chi2 / result.lines[k].threshold; };
  std::sort(result.worst_lines.begin(), result.worst_lines.end(), [&](int a, int b) { return excess(a) > excess(b); });

  for (int k = 0; k < static_cast<int>(edges.size()); ++k) {
    if (!edges[k].robust) continue;
    const Vector6 residual = whitened_residual(edges[k], poses.at(edges[k].from), poses.at(edges[k].to));
    result.registration_pulls.push_back({k, residual.norm()});
  }
  std::sort(result.registration_pulls.begin(), result.registration_pulls.end(),
            [](const EdgePull& a, const EdgePull& b) { return a.whitened_norm > b.whitened_norm; });
  return result;
}

}  // namespace bathyslam
