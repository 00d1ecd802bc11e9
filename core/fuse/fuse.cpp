#include "core/fuse/fuse.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/types/format.h"

namespace bathyslam {

GridFuser::GridFuser(const LocalOrigin& origin, const FuseConfig& config) : origin_(origin), config_(config) {
  if (!(config.resolution_m > 0)) throw std::invalid_argument("fuse: resolution must be positive");
  if (config.min_soundings < 1) throw std::invalid_argument("fuse: min_soundings must be at least 1");
}

GridFuser::Block& GridFuser::block_at(std::int64_t block_col, std::int64_t block_row) {
  const std::uint64_t key = (static_cast<std::uint64_t>(block_col) << 32) ^ (static_cast<std::uint64_t>(block_row) & 0xFFFFFFFFu);
  if (key == last_key_) return *last_block_;
  std::unique_ptr<Block>& block = blocks_[key];
  if (!block) block = std::make_unique<Block>(kBlockSize * kBlockSize);
  last_key_ = key;
  last_block_ = block.get();
  return *block;
}

void GridFuser::add(std::span<const Eigen::Vector3f> points, const Eigen::Isometry3d& pose) {
  // Place in CRS coordinates (map frame + origin) so that cells fall on the CRS-anchored lattice.
  Eigen::Isometry3d to_crs = pose;
  to_crs.translation() += Eigen::Vector3d(origin_.easting, origin_.northing, 0);
  const double inv_res = 1.0 / config_.resolution_m;
  for (const Eigen::Vector3f& p : points) {
    const Eigen::Vector3d q = to_crs * p.cast<double>();
    const auto col = static_cast<std::int64_t>(std::floor(q.x() * inv_res));
    const auto row = static_cast<std::int64_t>(std::floor(q.y() * inv_res));
    Block& block = block_at(col >> kBlockBits, row >> kBlockBits);  // >> floors negatives (C++20)
    Cell& c = block[((row & (kBlockSize - 1)) << kBlockBits) | (col & (kBlockSize - 1))];
    ++c.n;
    const double delta = q.z() - c.mean;
    c.mean += delta / c.n;
    c.m2 += delta * (q.z() - c.mean);
  }
  soundings_ += points.size();
}

GridRaster GridFuser::raster() const {
  const auto min_n = static_cast<std::uint32_t>(config_.min_soundings);
  // Decodes a block key and visits its cells with their global (col, row).
  auto for_each_cell = [](std::uint64_t key, const Block& block, auto&& visit) {
    const auto block_col = static_cast<std::int64_t>(static_cast<std::int32_t>(key >> 32));
    const auto block_row = static_cast<std::int64_t>(static_cast<std::int32_t>(key & 0xFFFFFFFFu));
    for (int y = 0; y < kBlockSize; ++y) {
      for (int x = 0; x < kBlockSize; ++x) {
        visit(block_col * kBlockSize + x, block_row * kBlockSize + y, block[(y << kBlockBits) | x]);
      }
    }
  };
  std::int64_t col_lo = std::numeric_limits<std::int64_t>::max(), col_hi = std::numeric_limits<std::int64_t>::min();
  std::int64_t row_lo = col_lo, row_hi = col_hi;
  for (const auto& [key, block] : blocks_) {
    for_each_cell(key, *block, [&](std::int64_t col, std::int64_t row, const Cell& c) {
      if (c.n < min_n) return;
      col_lo = std::min(col_lo, col);
      col_hi = std::max(col_hi, col);
      row_lo = std::min(row_lo, row);
      row_hi = std::max(row_hi, row);
    });
  }
  GridGeometry geometry;
  geometry.resolution_m = config_.resolution_m;
  if (col_lo > col_hi) return GridRaster::no_data(geometry);
  const double cells = static_cast<double>(col_hi - col_lo + 1) * static_cast<double>(row_hi - row_lo + 1);
  const bool over_limit = config_.max_cells > 0 && cells > static_cast<double>(config_.max_cells);
  if (over_limit || col_hi - col_lo >= std::numeric_limits<int>::max() || row_hi - row_lo >= std::numeric_limits<int>::max()) {
    throw std::length_error(format("map: the soundings cover %.0f m × %.0f m: %.0f cells at %g m, over the limit of %llu",
                                   static_cast<double>(col_hi - col_lo + 1) * config_.resolution_m,
                                   static_cast<double>(row_hi - row_lo + 1) * config_.resolution_m, cells,
                                   config_.resolution_m, static_cast<unsigned long long>(config_.max_cells)));
  }
  geometry.left = col_lo;
  geometry.top = row_hi;
  geometry.width = static_cast<int>(col_hi - col_lo + 1);
  geometry.height = static_cast<int>(row_hi - row_lo + 1);
  GridRaster out = GridRaster::no_data(geometry);
  for (const auto& [key, block] : blocks_) {
    for_each_cell(key, *block, [&](std::int64_t col, std::int64_t row, const Cell& c) {
      if (c.n < min_n) return;
      const std::size_t i = geometry.index(col, row);
      out.elevation[i] = static_cast<float>(c.mean);
      // Sample standard deviation: unknown, not zero, from a single sounding.
      out.uncertainty[i] = c.n > 1 ? static_cast<float>(std::sqrt(c.m2 / (c.n - 1))) : std::numeric_limits<float>::quiet_NaN();
      out.count[i] = static_cast<float>(c.n);
    });
  }
  return out;
}

GridRaster fuse_submaps(const SubmapSet& set, std::span<const Eigen::Isometry3d> poses, const FuseConfig& config) {
  if (poses.size() != set.submaps.size()) {
    throw std::invalid_argument("fuse: " + std::to_string(poses.size()) + " poses for " +
                                std::to_string(set.submaps.size()) + " submaps");
  }
  GridFuser fuser(set.origin, config);
  for (std::size_t i = 0; i < set.submaps.size(); ++i) fuser.add(set.submaps[i].points, poses[i]);
  return fuser.raster();
}

}  // namespace bathyslam
