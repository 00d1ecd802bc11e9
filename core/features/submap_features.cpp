#include "core/features/submap_features.h"

namespace bathyslam {

SubmapFeatures extract_features(const Submap& submap, const GridConfig& grid, const KeypointConfig& keypoints) {
  const TerrainGrid terrain = grid_terrain(submap.points, grid);
  return {detect_keypoints(terrain, keypoints), terrain.valid_cells(), terrain};
}

}  // namespace bathyslam
