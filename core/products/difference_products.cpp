#include "core/products/difference_products.h"

#include <array>
#include <fstream>

#include <nlohmann/json.hpp>

#include "core/io/file_bytes.h"
#include "core/tiles/gdal_raster.h"
#include "core/tiles/geotiff_writer.h"

namespace bathyslam {

std::vector<std::pair<int, int>> difference_pairs(int surveys) {
  std::vector<std::pair<int, int>> pairs;
  for (int before = 0; before < surveys; ++before) {
    for (int after = before + 1; after < surveys; ++after) {
      if (surveys <= kAllDifferencesUpTo || before == 0 || after == before + 1) pairs.emplace_back(before, after);
    }
  }
  return pairs;
}

DifferenceProducts write_difference_products(const PipelineResult& result, const SurveyMetadata& survey,
                                             const FuseConfig& fuse, int before, int after,
                                             const DifferenceConfig& config, const std::filesystem::path& dir) {
  DifferenceProducts out;
  out.stem = "difference_" + std::to_string(before + 1) + "_" + std::to_string(after + 1);
  out.map = difference_map(fuse_survey(result.submaps, result.optimized_poses, before, fuse),
                           fuse_survey(result.submaps, result.optimized_poses, after, fuse), config);
  const DifferenceMap& d = out.map;
  nlohmann::json areas = nlohmann::json::array();
  for (const ChangedArea& area : d.areas) {
    areas.push_back({{"easting", area.easting}, {"northing", area.northing},
                     {"area_m2", area.area_m2}, {"gained_m3", area.gained_m3}, {"lost_m3", area.lost_m3},
                     {"largest_change_m", area.largest_change_m}});
  }
  out.summary = {{"before", before + 1}, {"after", after + 1}, {"crs", survey.crs},
                 {"file", d.cells_compared > 0 ? nlohmann::json(out.stem + ".tif") : nlohmann::json(nullptr)},
                 {"k_sigma", config.k_sigma}, {"cell_m", d.geometry.resolution_m},
                 {"cells_compared", d.cells_compared}, {"cells_significant", d.cells_significant},
                 {"registration_sigma_m", {{"vertical", d.sigma_vertical_m}, {"horizontal", d.sigma_horizontal_m}}},
                 {"offset_window_m", config.offset_window_m}, {"local_offset_rms_m", d.offset_rms_m},
                 {"changed_areas", areas}};
  if (d.cells_compared == 0) return out;
  const std::array<NamedBand, 4> bands{
      {{"change", &d.change}, {"sigma", &d.sigma}, {"significant", &d.significant}, {"local_offset", &d.offset}}};
  write_geotiff(d.geometry, bands, survey.crs, dir / (out.stem + ".tif"));
  const std::filesystem::path path = dir / (out.stem + ".json");
  std::ofstream file(path);
  file << out.summary.dump(2) << '\n';
  close_checked(file, path);
  return out;
}

}  // namespace bathyslam
