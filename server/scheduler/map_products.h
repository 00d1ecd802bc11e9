#pragma once
// The map products of a finished pipeline run, as bytes for the database: the fused grid cut
// into the fixed tile pyramid (COG GeoTIFF, OpenVDB and a PNG quicklook per tile), the whole map
// as one COG, the grid's description, and the hillshade (and, for SLAM configurations, the
// difference against dead reckoning) for the report. Core's writers write files, so the files
// go through a scratch folder.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/fuse/fuse.h"
#include "core/pipeline/pipeline.h"
#include "server/storage/result_store.h"

namespace bathyslam::server {

struct MapProducts {
  std::vector<std::pair<storage::TileKey, storage::Bytes>> tiles;  // the whole map is format "cog" and "bag"
  storage::MapGrid grid;
  std::map<std::string, storage::Bytes> plots;  // map.png, map_difference.png
};

// Nothing (no tiles, levels 0) when no cell has enough soundings.
MapProducts make_map_products(const PipelineResult& result, const SurveyMetadata& survey, const FuseConfig& fuse,
                              const std::filesystem::path& scratch);

}  // namespace bathyslam::server
