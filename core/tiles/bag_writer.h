#pragma once
// BAG export (Bathymetry Attributed Grid, the ONS/IHO format: HDF5 with elevation, uncertainty
// and ISO 19115 metadata) through GDAL's BAG driver. Elevation is the fused map's (metres, up,
// negative below the datum, as BAG stores it); uncertainty is the cells' sounding standard
// deviation (BAG's "raw_std_dev"). Cells without data hold BAG's null value, 1 000 000.
#include <filesystem>
#include <string>
#include <string_view>

#include "core/fuse/grid.h"

namespace bathyslam {

inline constexpr float kBagNoData = 1.0e6f;

struct BagMetadata {
  std::string abstract;      // what the grid is
  std::string process_step;  // how it was made
  std::string organisation = "bathyslam";
};

// The metadata of a survey's fused map made by one pipeline configuration.
BagMetadata map_bag_metadata(const std::string& survey_name, const std::string& configuration);

// Writes `raster` (cells in `crs`, an "EPSG:<code>") to `path`; throws std::runtime_error naming
// the path when GDAL cannot.
void write_bag(const GridRaster& raster, std::string_view crs, const BagMetadata& metadata,
               const std::filesystem::path& path);

}  // namespace bathyslam
