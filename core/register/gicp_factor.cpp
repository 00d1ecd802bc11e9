#include "core/register/gicp_factor.h"

#include "core/register/parallel_chunks.h"

namespace bathyslam {
namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

// Points of `cloud` whose horizontal position, moved by `cloud_to_other`, falls inside the
// other cloud's box widened by `margin_m`: crop_to_overlap's test, in float like it.
template <typename Keep>
void in_box(const GicpCloud& cloud, const GicpCloud& other, const Eigen::Isometry3d& cloud_to_other, double margin_m,
            Keep&& keep) {
  const Eigen::Vector2f lo = other.lo.array() - static_cast<float>(margin_m);
  const Eigen::Vector2f hi = other.hi.array() + static_cast<float>(margin_m);
  const Eigen::Isometry3f t = cloud_to_other.cast<float>();
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector2f q = (t * cloud.points[i]).head<2>();
    keep(i, (q.array() >= lo.array()).all() && (q.array() <= hi.array()).all());
  }
}

}  // namespace

GicpOverlap gicp_overlap(const GicpCloud& target, const GicpCloud& source, const Eigen::Isometry3d& source_to_target,
                         double margin_m, int threads) {
  GicpOverlap o;
  in_box(source, target, source_to_target, margin_m, [&](std::size_t i, bool inside) {
    if (inside) o.source_points.push_back(static_cast<uint32_t>(i));
  });
  o.target_allowed.assign(target.points.size(), 0);
  std::vector<uint32_t> target_points;
  in_box(target, source, source_to_target.inverse(), margin_m, [&](std::size_t i, bool inside) {
    o.target_allowed[i] = inside;
    if (inside) target_points.push_back(static_cast<uint32_t>(i));
  });
  o.target_points = target_points.size();
  source.ensure_normals(o.source_points, threads);
  target.ensure_normals(target_points, threads);
  return o;
}

GicpLinearisation& GicpLinearisation::operator+=(const GicpLinearisation& other) {
  hessian += other.hessian;
  gradient += other.gradient;
  regularisation += other.regularisation;
  cost += other.cost;
  sq_distance_sum += other.sq_distance_sum;
  correspondences += other.correspondences;
  return *this;
}

namespace {

struct Associations {
  std::vector<GicpCorrespondence> list;
  Associations& operator+=(const Associations& other) {
    list.insert(list.end(), other.list.begin(), other.list.end());
    return *this;
  }
};

}  // namespace

std::vector<GicpCorrespondence> associate_gicp(const GicpCloud& target, const GicpCloud& source,
                                               const GicpOverlap& overlap, const Eigen::Isometry3d& source_to_target,
                                               double max_distance_m, int threads) {
  const Eigen::Isometry3f moved_by = source_to_target.cast<float>();
  const float max_sq = static_cast<float>(max_distance_m * max_distance_m);
  const uint8_t* allowed = overlap.target_allowed.empty() ? nullptr : overlap.target_allowed.data();
  return parallel_sum<Associations>(overlap.source_points.size(), threads,
                                    [&](Associations& found, std::size_t begin, std::size_t end) {
    found.list.reserve(end - begin);
    for (std::size_t k = begin; k < end; ++k) {
      const uint32_t i = overlap.source_points[k];
      uint32_t j = 0;
      float sq_distance = 0;
      if (target.tree->nearest(moved_by * source.points[i], max_sq, allowed, j, sq_distance)) found.list.push_back({i, j});
    }
  }).list;
}

GicpLinearisation linearise_gicp(const GicpCloud& target, const GicpCloud& source,
                                 const std::vector<GicpCorrespondence>& correspondences,
                                 const Eigen::Isometry3d& source_to_target, const Eigen::Vector3d& pivot, int threads,
                                 bool with_regularisation) {
  const Eigen::Matrix3d r = source_to_target.rotation();
  return parallel_sum<GicpLinearisation>(correspondences.size(), threads,
                                         [&](GicpLinearisation& sum, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const uint32_t i = correspondences[k].source, j = correspondences[k].target;
      const Eigen::Vector3d x = source_to_target * source.points[i].cast<double>();
      const Eigen::Vector3d d = x - target.points[j].cast<double>();
      // C_q + R C_p Rᵀ with C = I - (1 - ε) n nᵀ (gicp_cloud.h).
      const Eigen::Vector3d n_target = target.normals[j].cast<double>();
      const Eigen::Vector3d n_source = r * source.normals[i].cast<double>();
      const Eigen::Matrix3d combined = 2 * Eigen::Matrix3d::Identity() - (1 - GicpCloud::kPlaneEpsilon) *
                                       (n_target * n_target.transpose() + n_source * n_source.transpose());
      const Eigen::Matrix3d m = combined.inverse();
      Eigen::Matrix<double, 3, 6> jacobian;
      jacobian.leftCols<3>().setIdentity();
      jacobian.rightCols<3>() = -skew(x - pivot);
      const Eigen::Matrix<double, 6, 3> jt_m = jacobian.transpose() * m;
      sum.hessian.noalias() += jt_m * jacobian;
      sum.gradient.noalias() += jt_m * d;
      if (with_regularisation) sum.regularisation.noalias() += 0.5 * jacobian.transpose() * jacobian;
      sum.cost += 0.5 * d.dot(m * d);
      sum.sq_distance_sum += d.squaredNorm();
      ++sum.correspondences;
    }
  });
}

GicpLinearisation linearise_gicp(const GicpCloud& target, const GicpCloud& source, const GicpOverlap& overlap,
                                 const Eigen::Isometry3d& source_to_target, const Eigen::Vector3d& pivot,
                                 double max_distance_m, int threads, bool with_regularisation) {
  return linearise_gicp(target, source,
                        associate_gicp(target, source, overlap, source_to_target, max_distance_m, threads),
                        source_to_target, pivot, threads, with_regularisation);
}

}  // namespace bathyslam
