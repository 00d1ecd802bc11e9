#include "core/graph/robust_kernel.h"

#include <stdexcept>

namespace bathyslam {

DcsLoss::DcsLoss(double phi) : phi_(phi) {
  if (!(phi > 0)) throw std::invalid_argument("DCS needs Φ > 0");
}

void DcsLoss::Evaluate(double s, double rho[3]) const {
  if (s <= phi_) {
    rho[0] = s;
    rho[1] = 1.0;
    rho[2] = 0.0;
    return;
  }
  const double sum = s + phi_;
  rho[0] = phi_ * (3.0 * s - phi_) / sum;
  rho[1] = 4.0 * phi_ * phi_ / (sum * sum);
  rho[2] = -8.0 * phi_ * phi_ / (sum * sum * sum);
}

ceres::LossFunction* registration_loss(const GraphConfig& config) {
  switch (config.robust_kernel) {
    case RobustKernel::huber: return new ceres::HuberLoss(config.huber_delta);
    case RobustKernel::dcs: return new DcsLoss(config.dcs_phi);
  }
  throw std::invalid_argument("unknown robust kernel");
}

}  // namespace bathyslam
