#include "core/register/gicp_factor.h"

#include <algorithm>
#include <cmath>

#include "core/parallel/parallel_chunks.h"

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
void in_box(const std::vector<Eigen::Vector3f>& points, const GicpCloud& other, const Eigen::Isometry3d& cloud_to_other,
            double margin_m, Keep&& keep) {
  const Eigen::Vector2f lo = other.lo.array() - static_cast<float>(margin_m);
  const Eigen::Vector2f hi = other.hi.array() + static_cast<float>(margin_m);
  const Eigen::Isometry3f t = cloud_to_other.cast<float>();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2f q = (t * points[i]).head<2>();
    keep(i, (q.array() >= lo.array()).all() && (q.array() <= hi.array()).all());
  }
}

}  // namespace

GicpOverlap gicp_overlap(const GicpCloud& target, const GicpCloud& source, const Eigen::Isometry3d& source_to_target,
                         double margin_m, int threads) {
  GicpOverlap o;
  in_box(source.points, target, source_to_target, margin_m, [&](std::size_t i, bool inside) {
    if (inside) o.source_points.push_back(static_cast<uint32_t>(i));
  });
  o.target_allowed.assign(target.points.size(), 0);
  std::vector<uint32_t> target_points;
  in_box(target.points, source, source_to_target.inverse(), margin_m, [&](std::size_t i, bool inside) {
    o.target_allowed[i] = inside;
    if (inside) target_points.push_back(static_cast<uint32_t>(i));
  });
  in_box(source.soundings, target, source_to_target, margin_m, [&](std::size_t, bool inside) {
    o.source_soundings += inside ? 1 : 0;
  });
  o.target_soundings_allowed.assign(target.soundings.size(), 0);
  in_box(target.soundings, source, source_to_target.inverse(), margin_m, [&](std::size_t i, bool inside) {
    o.target_soundings_allowed[i] = inside;
  });
  o.target_points = target_points.size();
  source.ensure_normals(o.source_points, threads);
  target.ensure_normals(target_points, threads);
  return o;
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

Associator::Associator(const GicpCloud& target, const GicpCloud& source, const GicpOverlap& overlap,
                       double max_distance_m)
    : target_(target),
      source_(source),
      overlap_(overlap),
      gate_m_(static_cast<float>(max_distance_m)),
      // A quarter beyond the gate: a point with no neighbour then is searched again only after it
      // has moved by a quarter of the gate.
      search_m_(static_cast<float>(1.25 * max_distance_m)),
      remembered_(overlap.source_points.size()),
      candidates_(overlap.source_points.size() * kCandidates) {}

std::vector<GicpCorrespondence> Associator::at(const Eigen::Isometry3d& source_to_target, int threads) {
  // Float rounding of the distances and of the moved points, with room to spare.
  constexpr float kSlackM = 1e-4f;
  const Eigen::Isometry3f moved_by = source_to_target.cast<float>();
  const uint8_t* allowed = overlap_.target_allowed.empty() ? nullptr : overlap_.target_allowed.data();
  struct Found {
    Associations associations;
    std::size_t searches = 0;
    Found& operator+=(const Found& o) {
      associations += o.associations;
      searches += o.searches;
      return *this;
    }
  };
  Found all = parallel_sum<Found>(overlap_.source_points.size(), threads, [&](Found& found, std::size_t begin, std::size_t end) {
    found.associations.list.reserve(end - begin);
    float sq_distances[kCandidates];
    for (std::size_t k = begin; k < end; ++k) {
      const uint32_t i = overlap_.source_points[k];
      const Eigen::Vector3f x = moved_by * source_.points[i];
      Remembered& r = remembered_[k];
      uint32_t* listed = &candidates_[k * kCandidates];
      // The nearest candidate now, and the farthest (what bounds a new search).
      float nearest_sq = INFINITY, farthest_sq = 0;
      uint32_t nearest = 0;
      for (uint32_t c = 0; c < r.candidates; ++c) {
        const float d = (x - target_.points[listed[c]]).squaredNorm();
        if (d < nearest_sq) nearest_sq = d, nearest = listed[c];
        farthest_sq = std::max(farthest_sq, d);
      }
      const float moved = (x - r.searched_at).norm();  // NaN, so not below anything, if never searched
      const float answer_m = std::min(std::sqrt(nearest_sq), gate_m_);
      if (!(answer_m + kSlackM < r.reach_m - moved)) {
        float bound = search_m_ * search_m_;
        if (r.candidates == kCandidates) bound = std::min(bound, farthest_sq * (1 + 1e-5f) + 1e-9f);
        r.candidates = static_cast<uint32_t>(target_.grid->nearest_within(x, kCandidates, bound, allowed, listed, sq_distances));
        r.searched_at = x;
        r.reach_m = std::sqrt(r.candidates == kCandidates ? sq_distances[kCandidates - 1] : bound);
        nearest_sq = r.candidates > 0 ? sq_distances[0] : INFINITY;
        nearest = listed[0];
        ++found.searches;
      }
      if (nearest_sq <= gate_m_ * gate_m_) found.associations.list.push_back({i, nearest});
    }
  });
  searches_ += all.searches;
  return std::move(all.associations.list);
}

RegistrationQuality sampled_overlap_quality(const GicpCloud& target, const GicpCloud& source, const GicpOverlap& overlap,
                                            const Eigen::Isometry3d& source_to_target, double max_distance_m,
                                            int threads) {
  // Weighted by the soundings each sample point stands for.
  struct Within {
    double represented = 0, within = 0, sq_distance_sum = 0;
    Within& operator+=(const Within& o) {
      represented += o.represented;
      within += o.within;
      sq_distance_sum += o.sq_distance_sum;
      return *this;
    }
  };
  const Eigen::Isometry3f moved_by = source_to_target.cast<float>();
  const float max_sq = static_cast<float>(max_distance_m * max_distance_m);
  const uint8_t* allowed = overlap.target_soundings_allowed.empty() ? nullptr : overlap.target_soundings_allowed.data();
  const Within within = parallel_sum<Within>(overlap.source_points.size(), threads,
                                             [&](Within& sum, std::size_t begin, std::size_t end) {
    uint32_t index = 0;
    float sq_distance = 0;
    for (std::size_t k = begin; k < end; ++k) {
      const uint32_t i = overlap.source_points[k];
      const double weight = source.represents[i];
      sum.represented += weight;
      if (target.sounding_grid->nearest_within(moved_by * source.points[i], 1, max_sq, allowed, &index, &sq_distance) == 1) {
        sum.within += weight;
        sum.sq_distance_sum += weight * sq_distance;
      }
    }
  });
  RegistrationQuality q;
  if (!(within.within > 0)) return q;
  q.fitness = within.within / within.represented;
  q.overlap_points = static_cast<std::size_t>(std::llround(q.fitness * static_cast<double>(overlap.source_soundings)));
  q.overlap_points = std::max<std::size_t>(q.overlap_points, 1);  // some point overlaps: not "no overlap"
  q.overlap_mse_m2 = within.sq_distance_sum / within.within;
  return q;
}

std::vector<GicpCorrespondence> associate_gicp(const GicpCloud& target, const GicpCloud& source,
                                               const GicpOverlap& overlap, const Eigen::Isometry3d& source_to_target,
                                               double max_distance_m, int threads) {
  return Associator(target, source, overlap, max_distance_m).at(source_to_target, threads);
}

namespace {

// Σ Jᵀ M J and Σ Jᵀ M d by their 3×3 blocks, with J = [I, -[y]×], y = x - c, so that a
// correspondence costs a few 3×3 products instead of 6×6 ones; and Σ y, Σ y yᵀ, from which the
// regularisation Σ Jᵀ ½ J follows in closed form (it does not depend on M).
struct NormalEquationSums {
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();         // Σ M
  Eigen::Matrix3d m_skew = Eigen::Matrix3d::Zero();    // Σ M [y]×
  Eigen::Matrix3d skew_m_skew = Eigen::Matrix3d::Zero();  // Σ [y]× M [y]×
  Eigen::Vector3d md = Eigen::Vector3d::Zero();        // Σ M d
  Eigen::Vector3d y_cross_md = Eigen::Vector3d::Zero();  // Σ y × M d
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  Eigen::Matrix3d yy = Eigen::Matrix3d::Zero();
  double cost = 0;
  std::size_t correspondences = 0;

  NormalEquationSums& operator+=(const NormalEquationSums& o) {
    m += o.m;
    m_skew += o.m_skew;
    skew_m_skew += o.skew_m_skew;
    md += o.md;
    y_cross_md += o.y_cross_md;
    y += o.y;
    yy += o.yy;
    cost += o.cost;
    correspondences += o.correspondences;
    return *this;
  }

  GicpLinearisation linearisation(bool with_regularisation) const {
    GicpLinearisation out;
    // JᵀMJ = [[M, -M S], [S M, -S M S]] and JᵀMd = [M d, y × M d] for S = [y]× (Sᵀ = -S).
    out.hessian.topLeftCorner<3, 3>() = m;
    out.hessian.topRightCorner<3, 3>() = -m_skew;
    out.hessian.bottomLeftCorner<3, 3>() = -m_skew.transpose();
    out.hessian.bottomRightCorner<3, 3>() = -skew_m_skew;
    out.gradient << md, y_cross_md;
    if (with_regularisation) {
      // ½ JᵀJ = ½ [[I, -S], [S, |y|² I - y yᵀ]], summed.
      const double n = static_cast<double>(correspondences);
      out.regularisation.topLeftCorner<3, 3>() = 0.5 * n * Eigen::Matrix3d::Identity();
      out.regularisation.topRightCorner<3, 3>() = -0.5 * skew(y);
      out.regularisation.bottomLeftCorner<3, 3>() = 0.5 * skew(y);
      out.regularisation.bottomRightCorner<3, 3>() = 0.5 * (yy.trace() * Eigen::Matrix3d::Identity() - yy);
    }
    out.cost = cost;
    out.correspondences = correspondences;
    return out;
  }
};

}  // namespace

GicpLinearisation linearise_gicp(const GicpCloud& target, const GicpCloud& source,
                                 const std::vector<GicpCorrespondence>& correspondences,
                                 const Eigen::Isometry3d& source_to_target, const Eigen::Vector3d& pivot, int threads,
                                 bool with_regularisation) {
  const Eigen::Matrix3d r = source_to_target.rotation();
  return parallel_sum<NormalEquationSums>(correspondences.size(), threads,
                                          [&](NormalEquationSums& sum, std::size_t begin, std::size_t end) {
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
      const Eigen::Vector3d y = x - pivot;
      const Eigen::Matrix3d s = skew(y);
      const Eigen::Matrix3d ms = m * s;
      const Eigen::Vector3d md = m * d;
      sum.m += m;
      sum.m_skew += ms;
      sum.skew_m_skew.noalias() += s * ms;
      sum.md += md;
      sum.y_cross_md += y.cross(md);
      if (with_regularisation) {
        sum.y += y;
        sum.yy.noalias() += y * y.transpose();
      }
      sum.cost += 0.5 * d.dot(md);
      ++sum.correspondences;
    }
  }).linearisation(with_regularisation);
}

GicpLinearisation linearise_gicp(const GicpCloud& target, const GicpCloud& source, const GicpOverlap& overlap,
                                 const Eigen::Isometry3d& source_to_target, const Eigen::Vector3d& pivot,
                                 double max_distance_m, int threads, bool with_regularisation) {
  return linearise_gicp(target, source,
                        associate_gicp(target, source, overlap, source_to_target, max_distance_m, threads),
                        source_to_target, pivot, threads, with_regularisation);
}

}  // namespace bathyslam
