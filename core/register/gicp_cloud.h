#pragma once
// register (own GICP), preprocessing: a submap made ready for GICP once, whatever pairs it takes
// part in. All its soundings (float, submap frame) with a grid of columns over them, on which the
// overlap's quality is measured as PCL's wrapper measures it; and the registration sample: one
// sounding in every `soundings_per_sample` (the one nearest the centre of each column of a grid
// that holds that many a column), with its own grid and each sample point's covariance from its
// k nearest soundings, regularised to a plane; and the horizontal bounding box (for the overlap
// crop). PCL's GICP recomputes all of this for every pair; a submap is in 5-10 pairs.
//
// Why a sample: GICP's plane covariances make each correspondence a point-to-plane distance,
// and the plane is the k = 20 nearest soundings' (Table 1). Soundings closer together than that
// neighbourhood lie on the same planes and say the same thing about the pose; their noise is what
// differs, and the registration's error is set by the terrain's shape and the submaps' own
// distortion, not by that noise (docs/performance.md). The covariances still come from every
// sounding, so the planes are as good as before.
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include <Eigen/Core>

#include "core/filter/voxel_filter.h"
#include "core/register/column_grid.h"
#include "core/register/gicp.h"

namespace bathyslam {

struct GicpCloud {
  // Every sounding, and a grid of columns over them: what the overlap's quality is measured on.
  std::vector<Eigen::Vector3f> soundings;
  std::unique_ptr<ColumnGrid> sounding_grid;
  // The registration sample (its indices in `soundings` not kept: nothing needs them) and a grid
  // over it: what GICP associates and linearises. Each sample point stands for the soundings of
  // its column (`represents`), so that the overlap's quality and centroid, estimated from the
  // sample, weigh the soundings as the wrapper does and not the area.
  std::vector<Eigen::Vector3f> points;
  std::vector<uint32_t> represents;
  std::unique_ptr<ColumnGrid> grid;
  // Each sample point's covariance is plane-regularised: eigenvalues 1, 1, ε = 1e-3 with the
  // normal (the neighbourhood's least spread direction) taking ε, as in Segal et al. 2009 and
  // PCL's gicp_epsilon. That is I - (1 - ε) n nᵀ, so the unit normal says it all in 12 bytes
  // instead of a matrix's 36 (zero: too few neighbours, identity covariance). Computed on first
  // use (ensure_normals): a submap's pairs overlap only parts of it, and the k-nearest-neighbour
  // searches cost more than the grid.
  mutable std::vector<Eigen::Vector3f> normals;
  mutable std::vector<uint8_t> has_normal;
  mutable std::mutex normals_mutex;  // pairs registered in parallel may share the submap
  Eigen::Vector2f lo = Eigen::Vector2f::Constant(INFINITY), hi = Eigen::Vector2f::Constant(-INFINITY);  // x, y
  int neighbours = 0;  // the k the covariances were computed with

  // Computes the normals of the sample points `indices` not computed yet, from their k nearest
  // soundings, on `threads` threads. Normals once computed never change, so a pair may read its
  // own while another pair fills others.
  void ensure_normals(const std::vector<uint32_t>& indices, int threads = 1) const;

  static constexpr double kPlaneEpsilon = 1e-3;
  std::size_t bytes() const;  // what it holds, roughly (soundings, sample, normals, flags, grids)
  Eigen::Matrix3d covariance(std::size_t i) const {
    const Eigen::Vector3d n = normals[i].cast<double>();
    return Eigen::Matrix3d::Identity() - (1 - kPlaneEpsilon) * n * n.transpose();
  }
};

// Soundings, sample (one in `config.soundings_per_sample`; at 1, every sounding) and grids now;
// normals from the `config.neighbours` nearest soundings (the point itself included, as PCL counts
// them) when ensure_normals asks. A cloud with fewer soundings than that gets identity covariances.
std::shared_ptr<const GicpCloud> prepare_gicp_cloud(const Cloud& cloud, const GicpConfig& config);

// Each submap's GicpCloud, built on first use (thread-safe: pairs registered in parallel may ask
// for the same submap) and kept until `trim` drops it.
class GicpCloudCache {
 public:
  // `filtered(i)`: submap i's filtered cloud, made when the submap is first prepared (and again
  // if it is used after `trim` dropped it), so that a large survey's filtered clouds are never
  // all held at once. Called from several threads at a time.
  using FilteredCloud = std::function<Cloud::ConstPtr(std::size_t submap)>;
  GicpCloudCache(std::size_t submaps, FilteredCloud filtered, const GicpConfig& config);
  // Clouds filtered already (kept by the caller for as long as the cache).
  GicpCloudCache(const std::vector<Cloud::Ptr>& clouds, const GicpConfig& config);
  // Valid until the next `trim`.
  const GicpCloud& at(std::size_t submap);
  // Drops the prepared submaps used longest ago (by `at`) until the rest hold at most
  // `budget_bytes`; a survey's later pairs mostly reuse recent submaps (the line before), so
  // this bounds a large survey's memory at little cost. Not while any `at` result is in use.
  void trim(std::size_t budget_bytes);
  std::size_t bytes() const;

 private:
  struct Entry {
    std::once_flag built;
    std::shared_ptr<const GicpCloud> cloud;
    uint64_t last_used = 0;
  };
  FilteredCloud filtered_;
  GicpConfig config_;
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<Entry>> entries_;
  uint64_t uses_ = 0;
};

}  // namespace bathyslam
