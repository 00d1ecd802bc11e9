#include "core/register/column_grid.h"

#include <algorithm>
#include <cmath>

namespace bathyslam {
namespace {

// The k nearest so far, sorted, bounded by the search radius until k are found. k is a
// handful to a score: insertion into a sorted array beats a heap.
class NearestSoFar {
 public:
  NearestSoFar(std::size_t k, float max_sq_distance, uint32_t* indices, float* sq_distances)
      : k_(k), bound_(max_sq_distance), indices_(indices), sq_distances_(sq_distances) {}
  float worst() const { return count_ == k_ ? sq_distances_[k_ - 1] : bound_; }
  void add(float sq_distance, uint32_t index) {
    if (!(sq_distance < worst())) return;
    std::size_t at = count_ == k_ ? k_ - 1 : count_++;
    for (; at > 0 && sq_distances_[at - 1] > sq_distance; --at) {
      sq_distances_[at] = sq_distances_[at - 1];
      indices_[at] = indices_[at - 1];
    }
    sq_distances_[at] = sq_distance;
    indices_[at] = index;
  }
  std::size_t count() const { return count_; }

 private:
  std::size_t k_, count_ = 0;
  float bound_;
  uint32_t* indices_;
  float* sq_distances_;
};

}  // namespace

ColumnGrid::ColumnGrid(const std::vector<Eigen::Vector3f>& points, double points_per_column) {
  if (points.empty()) return;
  Eigen::Vector2f lo = points.front().head<2>(), hi = lo;
  for (const Eigen::Vector3f& p : points) {
    lo = lo.cwiseMin(p.head<2>());
    hi = hi.cwiseMax(p.head<2>());
  }
  const double area = std::max(static_cast<double>(hi.x() - lo.x()) * (hi.y() - lo.y()), 1e-6);
  cell_m_ = static_cast<float>(std::max(std::sqrt(points_per_column * area / static_cast<double>(points.size())), 1e-3));
  // A line of points (no width) would ask for one column per millimetre along it: at most 4096
  // columns a side, each point in the column its coordinates fall in (what the search relies on).
  cell_m_ = std::max(cell_m_, std::max(hi.x() - lo.x(), hi.y() - lo.y()) / 4096);
  const auto columns = [&](float extent) { return static_cast<int>(extent / cell_m_) + 1; };
  origin_ = lo;
  columns_x_ = columns(hi.x() - lo.x());
  columns_y_ = columns(hi.y() - lo.y());
  const auto column_of = [&](const Eigen::Vector3f& p) {
    const int x = std::min(static_cast<int>((p.x() - origin_.x()) / cell_m_), columns_x_ - 1);
    const int y = std::min(static_cast<int>((p.y() - origin_.y()) / cell_m_), columns_y_ - 1);
    return static_cast<std::size_t>(y) * columns_x_ + x;
  };
  // Counting sort by column.
  first_.assign(static_cast<std::size_t>(columns_x_) * columns_y_ + 1, 0);
  for (const Eigen::Vector3f& p : points) ++first_[column_of(p) + 1];
  for (std::size_t c = 1; c < first_.size(); ++c) first_[c] += first_[c - 1];
  std::vector<uint32_t> next(first_.begin(), first_.end() - 1);
  sorted_.resize(points.size());
  index_.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const uint32_t s = next[column_of(points[i])]++;
    sorted_[s] = points[i];
    index_[s] = static_cast<uint32_t>(i);
  }
}

std::size_t ColumnGrid::nearest_within(const Eigen::Vector3f& query, std::size_t k, float max_sq_distance,
                                       const uint8_t* allowed, uint32_t* indices, float* sq_distances) const {
  if (sorted_.empty() || k == 0 || !query.allFinite()) return 0;
  NearestSoFar nearest(k, max_sq_distance, indices, sq_distances);
  // The query's column, possibly outside the grid (clamped far enough not to overflow).
  const float fx = std::clamp((query.x() - origin_.x()) / cell_m_, -1e6f, 1e6f);
  const float fy = std::clamp((query.y() - origin_.y()) / cell_m_, -1e6f, 1e6f);
  const int cx = static_cast<int>(std::floor(fx)), cy = static_cast<int>(std::floor(fy));
  // How far the query is from its column's nearest side: ring r's columns are at least
  // (r - 1) cells plus this away.
  const float inside_m = cell_m_ * std::min({fx - cx, 1 - (fx - cx), fy - cy, 1 - (fy - cy)});
  const auto visit = [&](int x, int y) {
    const std::size_t column = static_cast<std::size_t>(y) * columns_x_ + x;
    for (uint32_t s = first_[column]; s < first_[column + 1]; ++s) {
      if (allowed != nullptr && !allowed[index_[s]]) continue;
      nearest.add((query - sorted_[s]).squaredNorm(), index_[s]);
    }
  };
  for (int r = 0;; ++r) {
    if (r > 0) {
      const float gap_m = (r - 1) * cell_m_ + inside_m;
      if (gap_m * gap_m >= nearest.worst()) break;
    }
    const int x0 = cx - r, x1 = cx + r, y0 = cy - r, y1 = cy + r;
    // The rings inside this one held the whole grid.
    if (r > 0 && x0 + 1 <= 0 && y0 + 1 <= 0 && x1 - 1 >= columns_x_ - 1 && y1 - 1 >= columns_y_ - 1) break;
    const int xa = std::max(x0, 0), xb = std::min(x1, columns_x_ - 1);
    for (int y = std::max(y0, 0); y <= std::min(y1, columns_y_ - 1); ++y) {
      if (y == y0 || y == y1) {
        for (int x = xa; x <= xb; ++x) visit(x, y);
      } else {
        if (x0 >= 0 && x0 < columns_x_) visit(x0, y);
        if (x1 >= 0 && x1 < columns_x_) visit(x1, y);
      }
    }
  }
  return nearest.count();
}

std::vector<uint32_t> ColumnGrid::central_points(std::vector<uint32_t>* column_points) const {
  std::vector<uint32_t> central;
  for (int y = 0; y < columns_y_; ++y) {
    for (int x = 0; x < columns_x_; ++x) {
      const std::size_t column = static_cast<std::size_t>(y) * columns_x_ + x;
      if (first_[column] == first_[column + 1]) continue;
      const Eigen::Vector2f centre = origin_ + cell_m_ * Eigen::Vector2f(x + 0.5f, y + 0.5f);
      uint32_t best = first_[column];
      for (uint32_t s = best + 1; s < first_[column + 1]; ++s) {
        if ((sorted_[s].head<2>() - centre).squaredNorm() < (sorted_[best].head<2>() - centre).squaredNorm()) best = s;
      }
      central.push_back(index_[best]);
      if (column_points != nullptr) column_points->push_back(first_[column + 1] - first_[column]);
    }
  }
  return central;
}

std::size_t ColumnGrid::bytes() const {
  return first_.size() * sizeof(uint32_t) + sorted_.size() * (sizeof(Eigen::Vector3f) + sizeof(uint32_t));
}

}  // namespace bathyslam
