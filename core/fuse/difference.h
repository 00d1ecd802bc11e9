#pragma once
// The difference of two epochs of one site (issue 33): per cell the depth change, its standard
// deviation and whether it is significant, and the changed areas with the volume each gained or
// lost. Both surfaces come from one graph (join_surveys), so the difference shows the seabed's
// change and what is left of the registration's error, which the standard deviation carries.
#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Geometry>

#include "core/fuse/fuse.h"
#include "core/submaps/submap.h"

namespace bathyslam {

// The map of one survey of a joined set (0-based, join order) at `poses`, from its submaps on
// survey lines: a turn's submaps are held by few registrations and swing the swath, and on `lake`
// they made most of the false changes (docs/sites.md).
GridRaster fuse_survey(const SubmapSet& set, std::span<const Eigen::Isometry3d> poses, int survey, const FuseConfig& config);

struct DifferenceConfig {
  double k_sigma = 3;  // a change is significant beyond k standard deviations
  int min_cells = 4;   // a changed area has at least this many significant cells (4-connected)
  // The registration leaves local offsets between the surveys (where one of them is held by few
  // registrations: line ends, turns): the median change in a window this wide around each cell is
  // taken for the registration's and removed. A change must cover less than half of it to stay.
  // 0: none removed.
  double offset_window_m = 100;
};

struct ChangedArea {
  double easting = 0, northing = 0;  // its centroid, in the CRS (the grid's lattice is the CRS's, grid.h)
  double area_m2 = 0;
  double gained_m3 = 0, lost_m3 = 0;  // elevation gained (deposit, an object) and lost (scour, dredging)
  double largest_change_m = 0;        // signed, the cell of largest |change|
};

struct DifferenceMap {
  GridGeometry geometry;                     // the cells both surfaces have
  std::vector<float> change, sigma, significant;  // after − before (m, up); its sigma; 1 or 0; NaN without both
  std::vector<float> offset;  // the local offset removed from `change` (offset_window_m)
  // The registration's part of the sigma, estimated from the cells themselves: a vertical offset
  // and a horizontal one, which moves a sloping cell by its slope times it.
  double sigma_vertical_m = 0, sigma_horizontal_m = 0;
  double offset_rms_m = 0;  // of the local offsets removed
  std::size_t cells_compared = 0, cells_significant = 0;
  std::vector<ChangedArea> areas;  // largest first
};

// after − before per cell, less the local offset around it. Each cell's sigma: both surfaces' standard error of their mean (the
// cells' spread over √count), and the registration's, sigma_vertical² + (slope · sigma_horizontal)²,
// fitted to the robust spread of the changes in bins of slope (most of a site does not change, so
// the spread of its differences is the registration's and the surfaces' noise).
DifferenceMap difference_map(const GridRaster& before, const GridRaster& after, const DifferenceConfig& config = {});

}  // namespace bathyslam
