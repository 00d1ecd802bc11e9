#include "core/register/registration_information.h"

#include <Eigen/Dense>

#include "core/search/flann_tree.h"

namespace bathyslam {
namespace {

constexpr double kPlaneEpsilon = 1e-3;  // GICP's (PCL's gicp_epsilon, Segal et al.)

using Tree = FlannTree;  // pcl::KdTreeFLANN's tree and neighbours, one query at a time

// Each point's neighbourhood covariance with its eigenvalues replaced by 1, 1, ε: a surface
// element, certain along its normal, uncertain across it, whatever the point spacing.
std::vector<Eigen::Matrix3d> plane_covariances(const Cloud& cloud, const Tree& tree, int neighbours) {
  std::vector<Eigen::Matrix3d> covariances(cloud.size());
  std::vector<int> index;
  std::vector<float> sq_distance;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const int found = tree.nearestKSearch(cloud[i], neighbours, index, sq_distance);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int k = 0; k < found; ++k) mean += cloud[index[k]].getVector3fMap().cast<double>();
    mean /= std::max(found, 1);
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    for (int k = 0; k < found; ++k) {
      const Eigen::Vector3d d = cloud[index[k]].getVector3fMap().cast<double>() - mean;
      scatter += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
    const Eigen::Matrix3d& u = eigen.eigenvectors();  // ascending: the normal first
    covariances[i] = u * Eigen::Vector3d(kPlaneEpsilon, 1.0, 1.0).asDiagonal() * u.transpose();
  }
  return covariances;
}

std::shared_ptr<Tree> tree_of(const Cloud& cloud) {
  auto tree = std::make_shared<Tree>();
  tree->setInputCloud(cloud.makeShared());
  return tree;
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

}  // namespace

std::vector<GicpTerm> gicp_terms(const Cloud& target, const Cloud& source, const Eigen::Isometry3d& source_to_target,
                                 const GicpConfig& config) {
  std::vector<GicpTerm> terms;
  if (target.empty() || source.empty()) return terms;
  const std::shared_ptr<Tree> target_tree = tree_of(target), source_tree = tree_of(source);
  const std::vector<Eigen::Matrix3d> target_covariances = plane_covariances(target, *target_tree, config.neighbours);
  const std::vector<Eigen::Matrix3d> source_covariances = plane_covariances(source, *source_tree, config.neighbours);
  const Eigen::Isometry3f t = source_to_target.cast<float>();
  const double max_sq = config.max_correspondence_m * config.max_correspondence_m;
  std::vector<int> index(1);
  std::vector<float> sq_distance(1);
  for (std::size_t i = 0; i < source.size(); ++i) {
    const Eigen::Vector3f moved = t * source[i].getVector3fMap();
    if (target_tree->nearestKSearch(pcl::PointXYZ(moved.x(), moved.y(), moved.z()), 1, index, sq_distance) != 1 ||
        sq_distance[0] > max_sq) {
      continue;
    }
    terms.push_back({source[i].getVector3fMap().cast<double>(), target[index[0]].getVector3fMap().cast<double>(),
                     source_covariances[i], target_covariances[index[0]]});
  }
  return terms;
}

double gicp_cost(const std::vector<GicpTerm>& terms, const Eigen::Isometry3d& source_to_target) {
  const Eigen::Matrix3d r = source_to_target.rotation();
  double cost = 0;
  for (const GicpTerm& term : terms) {
    const Eigen::Vector3d d = source_to_target * term.source - term.target;
    const Eigen::Matrix3d combined = term.target_covariance + r * term.source_covariance * r.transpose();
    cost += 0.5 * d.dot(combined.ldlt().solve(d));
  }
  return cost;
}

GicpHessian gicp_hessian(const std::vector<GicpTerm>& terms, const Eigen::Isometry3d& source_to_target,
                         const Eigen::Vector3d& anchor_in_source) {
  const Eigen::Matrix3d r = source_to_target.rotation();
  const Eigen::Vector3d anchor = source_to_target * anchor_in_source;
  GicpHessian h;
  h.correspondences = terms.size();
  for (const GicpTerm& term : terms) {
    // A point moved to q turns about the anchor c: q' = exp(δθ)(q - c) + c + δt, so
    // ∂q'/∂(δt, δθ) = [I, -[q - c]×].
    Eigen::Matrix<double, 3, 6> j;
    j.leftCols<3>().setIdentity();
    j.rightCols<3>() = -skew(source_to_target * term.source - anchor);
    const Eigen::Matrix3d m = (term.target_covariance + r * term.source_covariance * r.transpose()).inverse();
    h.hessian += j.transpose() * m * j;
    h.regularisation += 0.5 * j.transpose() * j;
  }
  return h;
}

GicpHessian gicp_hessian(const Cloud& target, const Cloud& source, const Eigen::Isometry3d& source_to_target,
                         const Eigen::Vector3d& anchor_in_source, const GicpConfig& config) {
  return gicp_hessian(gicp_terms(target, source, source_to_target, config), source_to_target, anchor_in_source);
}

Eigen::Matrix<double, 6, 1> shape_scales(const GicpHessian& hessian, const Eigen::Matrix<double, 6, 1>& best_sigmas) {
  // Σ JᵀJ's rotation diagonal over its translation one: each rotation axis's mean squared lever.
  const Eigen::Matrix<double, 6, 1> d = hessian.regularisation.diagonal();
  const Eigen::Vector3d lever = (d.tail<3>().array() / d.head<3>().array().max(1e-300)).sqrt().max(1e-9);
  Eigen::Matrix<double, 6, 1> scales;
  scales.head<3>() = best_sigmas.head<3>();
  scales(3) = best_sigmas(2) / lever(0);
  scales(4) = best_sigmas(2) / lever(1);
  scales(5) = std::sqrt(best_sigmas(0) * best_sigmas(1)) / lever(2);
  return scales;
}

Information6 observed_information(const GicpHessian& hessian, double quality_weight,
                                  const Eigen::Matrix<double, 6, 1>& best_sigmas, double full_share,
                                  double zero_share) {
  const Eigen::Matrix<double, 6, 1> scales = shape_scales(hessian, best_sigmas);
  const Matrix6 observed = hessian.hessian - hessian.regularisation;
  const Matrix6 whitened = scales.asDiagonal() * observed * scales.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Matrix6> eigen(0.5 * (whitened + whitened.transpose()));
  const double strongest = eigen.eigenvalues().maxCoeff();
  if (!(strongest > 0)) return Information6::Zero();
  Eigen::Matrix<double, 6, 1> shares;
  for (int k = 0; k < 6; ++k) {
    const double share = eigen.eigenvalues()(k) / strongest;
    shares(k) = share < zero_share ? 0.0 : std::min(1.0, share / full_share);
  }
  const Matrix6 shape = eigen.eigenvectors() * shares.asDiagonal() * eigen.eigenvectors().transpose();
  const Eigen::Matrix<double, 6, 1> unwhiten = best_sigmas.cwiseInverse();
  return quality_weight * unwhiten.asDiagonal() * shape * unwhiten.asDiagonal();
}

GicpHessian rotated(const GicpHessian& hessian, const Eigen::Matrix3d& rotation) {
  Matrix6 turn = Matrix6::Zero();
  turn.topLeftCorner<3, 3>() = rotation;
  turn.bottomRightCorner<3, 3>() = rotation;
  GicpHessian out = hessian;
  out.hessian = turn * hessian.hessian * turn.transpose();
  out.regularisation = turn * hessian.regularisation * turn.transpose();
  return out;
}

}  // namespace bathyslam
