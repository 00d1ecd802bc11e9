#pragma once
// register (own GICP), factors: the GICP cost of one pair at a pose, linearised. Each source
// point of the overlap finds its nearest target point within the gate (the column grid of the
// whole target, masked to its overlap); the pair contributes dᵀ M d with d = T p - q and
// M = (C_q + R C_p Rᵀ)⁻¹ (Segal et al. 2009), and the normal equations Σ Jᵀ M J, Σ Jᵀ M d for
// a perturbation about a pivot, all summed in double over threads with one reduction.
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/register/gicp.h"
#include "core/register/gicp_cloud.h"

namespace bathyslam {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// What registers: the source's sample points in the predicted overlap, and which target sample
// points are in it; and what the quality is measured on: which target soundings are in it, and
// how many source soundings.
struct GicpOverlap {
  std::vector<uint32_t> source_points;
  std::vector<uint8_t> target_allowed;  // one per target sample point
  std::size_t target_points = 0;        // how many are allowed
  std::vector<uint8_t> target_soundings_allowed;  // one per target sounding
  std::size_t source_soundings = 0;
};

// The same crop as crop_to_overlap (gicp.h) on both clouds, as indices and masks, with the
// normals of every sample point in it computed (GicpCloud::ensure_normals).
GicpOverlap gicp_overlap(const GicpCloud& target, const GicpCloud& source, const Eigen::Isometry3d& source_to_target,
                         double margin_m, int threads = 1);

// One source point of the overlap and its nearest allowed target point within the gate.
struct GicpCorrespondence {
  uint32_t source = 0, target = 0;
};

// Associates the overlap's source points with their nearest allowed target points within a
// gate, at pose after pose of one registration. GICP's later iterations move the source by
// centimetres, where the nearest neighbour is still among the few nearest of the last search.
// Each point keeps those `kCandidates` and how far the nearest unlisted point was then (`reach`:
// the next one, or the search's bound). After a move by δ every unlisted point is at least
// reach - δ away, so if the nearest candidate (or the gate, when none is within it) is closer
// than that, it is the answer (the triangle inequality) and the grid is not searched. Only the
// others are searched again, no farther than their farthest candidate now, so the answer is
// exactly a full search's.
class Associator {
 public:
  Associator(const GicpCloud& target, const GicpCloud& source, const GicpOverlap& overlap, double max_distance_m);

  // Every overlap source point's correspondence at `source_to_target`, in overlap order.
  std::vector<GicpCorrespondence> at(const Eigen::Isometry3d& source_to_target, int threads);
  std::size_t searches() const { return searches_; }

  // Enough that a decimetre step keeps most points' lists (their reach is ~1.5 sounding
  // spacings out), few enough that checking them costs less than a search.
  static constexpr std::size_t kCandidates = 4;

 private:
  struct Remembered {
    Eigen::Vector3f searched_at = Eigen::Vector3f::Constant(NAN);  // moved source point; NaN: never
    float reach_m = 0;         // every unlisted allowed target point was at least this far then
    uint32_t candidates = 0;   // how many are listed
  };
  const GicpCloud& target_;
  const GicpCloud& source_;
  const GicpOverlap& overlap_;
  float gate_m_, search_m_;
  std::vector<Remembered> remembered_;  // one per overlap source point
  std::vector<uint32_t> candidates_;    // kCandidates per overlap source point, nearest first
  std::size_t searches_ = 0;
};

// The overlap's quality at `source_to_target` as register_gicp measures it on every sounding
// (nearest target sounding within `max_distance_m`), estimated from the source's sample, each
// point weighing the soundings it stands for: fitness and mean squared distance, and the count
// within the gate as the fitness times the overlap's source soundings.
RegistrationQuality sampled_overlap_quality(const GicpCloud& target, const GicpCloud& source, const GicpOverlap& overlap,
                                            const Eigen::Isometry3d& source_to_target, double max_distance_m,
                                            int threads);

// One association from scratch (Associator::at).
std::vector<GicpCorrespondence> associate_gicp(const GicpCloud& target, const GicpCloud& source,
                                               const GicpOverlap& overlap, const Eigen::Isometry3d& source_to_target,
                                               double max_distance_m, int threads);

struct GicpLinearisation {
  // For x' = exp(δθ)(x - c) + c + δt of every moved source point x (target frame, pivot c):
  // ∂x'/∂(δt, δθ) = [I, -[x - c]×].
  Matrix6d hessian = Matrix6d::Zero();    // Σ Jᵀ M J
  Vector6d gradient = Vector6d::Zero();   // Σ Jᵀ M d
  Matrix6d regularisation = Matrix6d::Zero();  // Σ Jᵀ (½ I) J, only if asked for
  double cost = 0;                        // ½ Σ dᵀ M d
  std::size_t correspondences = 0;
};

// Linearises the cost of fixed correspondences at `source_to_target` about `pivot` (target frame).
GicpLinearisation linearise_gicp(const GicpCloud& target, const GicpCloud& source,
                                 const std::vector<GicpCorrespondence>& correspondences,
                                 const Eigen::Isometry3d& source_to_target, const Eigen::Vector3d& pivot, int threads,
                                 bool with_regularisation = false);

// Both at once: the correspondences at `source_to_target` within `max_distance_m`, linearised there.
GicpLinearisation linearise_gicp(const GicpCloud& target, const GicpCloud& source, const GicpOverlap& overlap,
                                 const Eigen::Isometry3d& source_to_target, const Eigen::Vector3d& pivot,
                                 double max_distance_m, int threads, bool with_regularisation = false);

}  // namespace bathyslam
