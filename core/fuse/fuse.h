#pragma once
// fuse (docs/design.md pipeline): every sounding placed by its submap's pose onto the CRS-anchored
// grid; per cell the mean elevation, the standard deviation and the count.
#include <cstdint>
#include <memory>
#include <span>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>

#include "core/fuse/grid.h"
#include "core/submaps/submap.h"
#include "core/types/pose.h"

namespace bathyslam {

struct FuseConfig {
  double resolution_m = 0.5;
  int min_soundings = 3;  // fewer soundings in a cell: NoData (as the consistency grid's minimum)
  // The raster over the cells with data may hold at most this many cells (0: no limit). The
  // survey's extent is checked before the pipeline; this holds the optimized poses to it too,
  // should they scatter the soundings far beyond it.
  std::uint64_t max_cells = 0;
};

// Accumulates soundings one cloud at a time, keeping a running mean and sum of squared
// deviations per touched cell (Welford), so memory grows with the area covered, not with the
// number of soundings. Cells live in 64 × 64 blocks created on first touch.
class GridFuser {
 public:
  GridFuser(const LocalOrigin& origin, const FuseConfig& config = {});

  // Adds `points` (in some frame; z up after the pose) placed by `pose` (that frame -> map frame).
  void add(std::span<const Eigen::Vector3f> points, const Eigen::Isometry3d& pose);

  // The grid over the cells with at least `min_soundings` soundings (empty geometry if none).
  // Throws std::length_error when it would exceed `max_cells` (or a raster's int size).
  GridRaster raster() const;
  std::uint64_t soundings() const { return soundings_; }
  // Cells held in memory (whole blocks), whatever the number of soundings added.
  std::size_t allocated_cells() const { return blocks_.size() * kBlockSize * kBlockSize; }
  std::size_t allocated_bytes() const { return allocated_cells() * sizeof(Cell); }

 private:
  static constexpr int kBlockBits = 6;
  static constexpr int kBlockSize = 1 << kBlockBits;
  struct Cell {
    double mean = 0;
    double m2 = 0;  // sum of squared deviations from the mean
    std::uint32_t n = 0;
  };
  using Block = std::vector<Cell>;  // kBlockSize², row-major by (row, col) within the block

  Block& block_at(std::int64_t block_col, std::int64_t block_row);

  LocalOrigin origin_;
  FuseConfig config_;
  std::unordered_map<std::uint64_t, std::unique_ptr<Block>> blocks_;
  std::uint64_t last_key_ = ~std::uint64_t{0};
  Block* last_block_ = nullptr;  // soundings come in swaths: most hit the previous one's block
  std::uint64_t soundings_ = 0;
};

// The map of a submap set with one pose per submap (DR, optimized or any other), submap by submap.
GridRaster fuse_submaps(const SubmapSet& set, std::span<const Eigen::Isometry3d> poses, const FuseConfig& config = {});

}  // namespace bathyslam
