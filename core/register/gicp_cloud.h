#pragma once
// register (own GICP), preprocessing: a submap made ready for GICP once, whatever pairs it takes
// part in: its points (float, submap frame), a grid of columns over them, each point's covariance from
// its k nearest neighbours regularised to a plane, and its horizontal bounding box (for the
// overlap crop). PCL's GICP recomputes all of this for every pair; a submap is in 5-10 pairs.
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include <Eigen/Core>

#include "core/filter/voxel_filter.h"
#include "core/register/column_grid.h"

namespace bathyslam {

struct GicpCloud {
  std::vector<Eigen::Vector3f> points;
  // Each point's covariance is plane-regularised: eigenvalues 1, 1, ε = 1e-3 with the normal
  // (the neighbourhood's least spread direction) taking ε, as in Segal et al. 2009 and PCL's
  // gicp_epsilon. That is I - (1 - ε) n nᵀ, so the unit normal says it all in 12 bytes instead
  // of a matrix's 36 (zero: too few neighbours, identity covariance). Computed on first use
  // (ensure_normals): a submap's pairs overlap only parts of it, and the k-nearest-neighbour
  // searches cost more than the grid.
  mutable std::vector<Eigen::Vector3f> normals;
  mutable std::vector<uint8_t> has_normal;
  mutable std::mutex normals_mutex;  // pairs registered in parallel may share the submap
  std::unique_ptr<ColumnGrid> grid;
  Eigen::Vector2f lo = Eigen::Vector2f::Constant(INFINITY), hi = Eigen::Vector2f::Constant(-INFINITY);  // x, y
  int neighbours = 0;  // the k the covariances were computed with

  // Computes the normals of `indices` not computed yet, on `threads` threads. Normals once
  // computed never change, so a pair may read its own while another pair fills others.
  void ensure_normals(const std::vector<uint32_t>& indices, int threads = 1) const;

  static constexpr double kPlaneEpsilon = 1e-3;
  std::size_t bytes() const;  // what it holds, roughly (points, normals, flags, grid)
  Eigen::Matrix3d covariance(std::size_t i) const {
    const Eigen::Vector3d n = normals[i].cast<double>();
    return Eigen::Matrix3d::Identity() - (1 - kPlaneEpsilon) * n * n.transpose();
  }
};

// Points and grid now; normals from `neighbours` nearest points (the point itself included, as
// PCL counts them) when ensure_normals asks. A cloud with fewer points than that gets identity
// covariances.
std::shared_ptr<const GicpCloud> prepare_gicp_cloud(const Cloud& cloud, int neighbours);

// Each submap's GicpCloud, built on first use (thread-safe: pairs registered in parallel may ask
// for the same submap) and kept until `trim` drops it.
class GicpCloudCache {
 public:
  // `filtered(i)`: submap i's filtered cloud, made when the submap is first prepared (and again
  // if it is used after `trim` dropped it), so that a large survey's filtered clouds are never
  // all held at once. Called from several threads at a time.
  using FilteredCloud = std::function<Cloud::ConstPtr(std::size_t submap)>;
  GicpCloudCache(std::size_t submaps, FilteredCloud filtered, int neighbours);
  // Clouds filtered already (kept by the caller for as long as the cache).
  GicpCloudCache(const std::vector<Cloud::Ptr>& clouds, int neighbours);
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
  int neighbours_;
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<Entry>> entries_;
  uint64_t uses_ = 0;
};

}  // namespace bathyslam
