#pragma once
// OpenVDB export of a grid (a tile, usually): a FloatGrid "elevation" with one voxel per cell in
// the k = 0 slab, a FloatGrid "uncertainty" and an Int32Grid "count". Only cells with data are
// active; inactive voxels read as the background (NaN for elevation and uncertainty, 0 for count).
//
// Index space is the CRS-anchored lattice itself: voxel (i, j, 0) is global cell (col i, row j),
// so tiles of one level share an index space and combine without resampling. The transform
// scales by the cell size and shifts by half a cell, so the world position of a voxel is its cell
// centre in CRS coordinates (x easting, y northing, metres). Each grid's metadata repeats what a
// reader needs without knowing the convention: "crs", "resolution_m", "origin_easting_m" and
// "origin_northing_m" (the raster's south-west corner) and "origin_col"/"origin_row" (its
// south-west cell's index).
#include <filesystem>
#include <string_view>

#include "core/fuse/grid.h"

namespace bathyslam {

// Writes `raster` (cells in `crs`, an "EPSG:<code>") to `path`; throws std::runtime_error naming
// the path when OpenVDB cannot.
void write_vdb(const GridRaster& raster, std::string_view crs, const std::filesystem::path& path);

}  // namespace bathyslam
