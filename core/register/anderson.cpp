#include "core/register/anderson.h"

#include <Eigen/QR>

namespace bathyslam {

AndersonAcceleration::Vector6d AndersonAcceleration::next(const Vector6d& x, const Vector6d& g) {
  history_.push_back({g, g - x});
  if (static_cast<int>(history_.size()) > depth_ + 1) history_.pop_front();
  const int m = static_cast<int>(history_.size()) - 1;
  if (m == 0) return g;
  // γ = argmin |f_k - ΔF γ| over the differences of consecutive residuals; the next point is
  // G(x_k) - ΔG γ.
  Eigen::Matrix<double, 6, Eigen::Dynamic> delta_f(6, m), delta_g(6, m);
  for (int j = 0; j < m; ++j) {
    delta_f.col(j) = history_[j + 1].f - history_[j].f;
    delta_g.col(j) = history_[j + 1].g - history_[j].g;
  }
  const Eigen::VectorXd gamma = delta_f.completeOrthogonalDecomposition().solve(history_.back().f);
  if (!gamma.allFinite()) return g;
  return g - delta_g * gamma;
}

}  // namespace bathyslam
