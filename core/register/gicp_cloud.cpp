#include "core/register/gicp_cloud.h"

#include <algorithm>

#include <Eigen/Eigenvalues>

#include "core/parallel/parallel_chunks.h"

namespace bathyslam {
namespace {

// The unit normal of a neighbourhood. Mean and scatter in double about the first neighbour: float sums of squares of coordinates
// tens of metres from the origin would lose the centimetre structure that sets the normal.
Eigen::Vector3f plane_normal(const std::vector<Eigen::Vector3f>& points, const uint32_t* index, std::size_t found) {
  if (found < 3) return Eigen::Vector3f::Zero();
  const Eigen::Vector3d origin = points[index[0]].cast<double>();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sum_sq = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < found; ++k) {
    const Eigen::Vector3d d = points[index[k]].cast<double>() - origin;
    sum += d;
    sum_sq += d * d.transpose();
  }
  const double n = static_cast<double>(found);
  const Eigen::Matrix3d scatter = sum_sq / n - (sum / n) * (sum / n).transpose();
  // The closed form for 3x3 (several times faster than the iterative solver): only the normal,
  // the least spread direction, keeps its eigenvalue, and on a sounding neighbourhood it is well
  // apart from the other two.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(scatter);
  return eigen.eigenvectors().col(0).normalized().cast<float>();  // ascending: the normal first
}

}  // namespace

std::shared_ptr<const GicpCloud> prepare_gicp_cloud(const Cloud& cloud, const GicpConfig& config) {
  auto out = std::make_shared<GicpCloud>();
  const int neighbours = out->neighbours = config.neighbours;
  out->soundings.reserve(cloud.size());
  for (const pcl::PointXYZ& p : cloud) {
    out->soundings.push_back(p.getVector3fMap());
    out->lo = out->lo.cwiseMin(out->soundings.back().head<2>());
    out->hi = out->hi.cwiseMax(out->soundings.back().head<2>());
  }
  out->sounding_grid = std::make_unique<ColumnGrid>(out->soundings);
  if (config.soundings_per_sample <= 1) {
    out->points = out->soundings;
    out->represents.assign(out->points.size(), 1);
  } else {
    for (uint32_t i : ColumnGrid(out->soundings, config.soundings_per_sample).central_points(&out->represents)) {
      out->points.push_back(out->soundings[i]);
    }
  }
  out->grid = std::make_unique<ColumnGrid>(out->points);
  out->normals.assign(out->points.size(), Eigen::Vector3f::Zero());
  // Too few soundings for a neighbourhood: every covariance stays the identity.
  const bool none = neighbours < 3 || out->soundings.size() < static_cast<std::size_t>(neighbours);
  out->has_normal.assign(out->points.size(), none ? 1 : 0);
  return out;
}

void GicpCloud::ensure_normals(const std::vector<uint32_t>& indices, int threads) const {
  const std::lock_guard<std::mutex> lock(normals_mutex);
  std::vector<uint32_t> missing;
  for (uint32_t i : indices) {
    if (!has_normal[i]) {
      has_normal[i] = 1;  // also dedups repeated indices
      missing.push_back(i);
    }
  }
  const std::size_t k = static_cast<std::size_t>(neighbours);
  parallel_chunks(missing.size(), threads, [&](int, std::size_t begin, std::size_t end) {
    std::vector<uint32_t> index(k);
    std::vector<float> sq_distance(k);
    for (std::size_t m = begin; m < end; ++m) {
      const uint32_t i = missing[m];
      const std::size_t found =
          sounding_grid->nearest_within(points[i], k, INFINITY, nullptr, index.data(), sq_distance.data());
      normals[i] = plane_normal(soundings, index.data(), found);
    }
  });
}

std::size_t GicpCloud::bytes() const {
  return soundings.size() * sizeof(Eigen::Vector3f) +
         points.size() * (sizeof(Eigen::Vector3f) * 2 + sizeof(uint32_t) + sizeof(uint8_t)) +
         (sounding_grid ? sounding_grid->bytes() : 0) + (grid ? grid->bytes() : 0);
}

GicpCloudCache::GicpCloudCache(std::size_t submaps, FilteredCloud filtered, const GicpConfig& config)
    : filtered_(std::move(filtered)), config_(config), entries_(submaps) {}

GicpCloudCache::GicpCloudCache(const std::vector<Cloud::Ptr>& clouds, const GicpConfig& config)
    : GicpCloudCache(clouds.size(), [&clouds](std::size_t i) { return clouds[i]; }, config) {}
const GicpCloud& GicpCloudCache::at(std::size_t submap) {
  std::shared_ptr<Entry> entry;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    std::shared_ptr<Entry>& slot = entries_.at(submap);
    if (!slot) slot = std::make_shared<Entry>();
    slot->last_used = ++uses_;
    entry = slot;
  }
  std::call_once(entry->built, [&] { entry->cloud = prepare_gicp_cloud(*filtered_(submap), config_); });
  return *entry->cloud;
}

std::size_t GicpCloudCache::bytes() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::size_t sum = 0;
  for (const std::shared_ptr<Entry>& e : entries_) {
    if (e && e->cloud) sum += e->cloud->bytes();
  }
  return sum;
}

void GicpCloudCache::trim(std::size_t budget_bytes) {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::size_t> held;
  std::size_t sum = 0;
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    if (entries_[i] && entries_[i]->cloud) {
      held.push_back(i);
      sum += entries_[i]->cloud->bytes();
    }
  }
  std::sort(held.begin(), held.end(), [&](std::size_t a, std::size_t b) { return entries_[a]->last_used < entries_[b]->last_used; });
  for (std::size_t i : held) {
    if (sum <= budget_bytes) break;
    sum -= entries_[i]->cloud->bytes();
    entries_[i].reset();
  }
}

}  // namespace bathyslam
