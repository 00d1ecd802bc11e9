#pragma once
// robust_kernel: the losses on registration edges, as Ceres loss functions of the squared
// whitened residual s.
#include <ceres/loss_function.h>

#include "core/graph/pose_graph.h"

namespace bathyslam {

// Dynamic covariance scaling (Agarwal et al., ICRA 2013) as a robust kernel. DCS scales an edge's
// whitened residual by k(s) = min(1, 2Φ/(Φ + s)), so the edge's cost is k²s and, in the
// iteratively reweighted view Ceres takes, its weight in the normal equations is k². The kernel
// with that weight is the one whose derivative is k²:
//   s ≤ Φ:  ρ(s) = s
//   s > Φ:  ρ(s) = Φ(3s − Φ)/(s + Φ),  ρ'(s) = 4Φ²/(s + Φ)² = k(s)²,  ρ''(s) = −8Φ²/(s + Φ)³
// ρ and ρ' are continuous at Φ (Φ and 1) and ρ tends to 3Φ: an edge however wrong costs at most
// three times Φ, so it cannot hold the solution against the edges that agree. (g2o's DCS sets ρ =
// k²s with ρ' = k², which are not a function and its derivative.)
class DcsLoss : public ceres::LossFunction {
 public:
  explicit DcsLoss(double phi);
  void Evaluate(double s, double rho[3]) const override;

 private:
  double phi_;
};

// The loss GraphConfig selects for registration edges; the caller (Ceres' Problem) owns it.
ceres::LossFunction* registration_loss(const GraphConfig& config);

}  // namespace bathyslam
