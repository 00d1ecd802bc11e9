#pragma once
// The map products of a pipeline run, as files: the fused map as one COG (map.tif) and as BAG
// (map.bag), the tile pyramid (tiles/{level}/{col}_{row}.tif, .vdb and a .png quicklook), the
// hillshade (map.png)
// and, when registrations moved the map, its difference against dead reckoning
// (map_difference.png). The CLI writes them into its output folder; the service into scratch,
// from where it stores them.
#include <filesystem>
#include <string>
#include <vector>

#include "core/fuse/fuse.h"
#include "core/pipeline/pipeline.h"
#include "core/tiles/tile_files.h"
#include "core/types/survey.h"

namespace bathyslam {

struct MapFiles {
  bool written = false;  // false: no cell had enough soundings, and nothing was written
  GridGeometry geometry;
  TileFileCount tiles;
  std::vector<TileId> tile_ids;      // each as tiles/{tile_stem}.tif, .vdb and .png
  std::vector<std::string> plots;    // map.png, map_difference.png

  std::string summary() const;       // "map.tif, map.bag, map.png, 9 tiles on 3 levels, map_difference.png"
};

MapFiles write_map_products(const PipelineResult& result, const SurveyMetadata& survey, const FuseConfig& fuse,
                            const std::filesystem::path& dir);

}  // namespace bathyslam
