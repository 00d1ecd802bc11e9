#pragma once
// features: what the registration stage needs of one submap's terrain, made once per submap: its
// grid (for the uniqueness probe) and its TSD keypoints (for matching).
#include <vector>

#include "core/features/terrain_grid.h"
#include "core/features/tsd_keypoints.h"
#include "core/submaps/submap.h"

namespace bathyslam {

struct SubmapFeatures {
  std::vector<Keypoint> keypoints;
  int valid_cells = 0;
  TerrainGrid grid;  // kept for the uniqueness probe
};

SubmapFeatures extract_features(const Submap& submap, const GridConfig& grid, const KeypointConfig& keypoints);

}  // namespace bathyslam
