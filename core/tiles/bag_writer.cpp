#include "core/tiles/bag_writer.h"

#include <array>
#include <cmath>
#include <ctime>

#include <cpl_string.h>

#include "core/tiles/gdal_raster.h"
#include "core/types/format.h"

namespace bathyslam {
namespace {

// BAG has no NaN: a cell without a value holds the null value.
std::vector<float> with_bag_nulls(const std::vector<float>& values) {
  std::vector<float> out(values);
  for (float& v : out) {
    if (std::isnan(v)) v = kBagNoData;
  }
  return out;
}

}  // namespace

BagMetadata map_bag_metadata(const std::string& survey_name, const std::string& configuration) {
  return {"Bathymetry of survey '" + survey_name + "': mean elevation and standard deviation of the soundings per cell",
          "bathyslam: pings georeferenced by the navigation corrected with the '" + configuration +
              "' configuration (MCHS-SLAM pose graph), soundings fused per cell (mean, standard deviation)"};
}

void write_bag(const GridRaster& raster, std::string_view crs, const BagMetadata& metadata,
               const std::filesystem::path& path) {
  const std::string what = path.string() + ": cannot write BAG";
  const std::vector<float> elevation = with_bag_nulls(raster.elevation);
  const std::vector<float> uncertainty = with_bag_nulls(raster.uncertainty);
  const std::array<NamedBand, 2> bands{{{"elevation", &elevation}, {"uncertainty", &uncertainty}}};
  GdalDatasetPtr mem = memory_raster(raster.geometry, crs, bands, kBagNoData, what);

  // The variables of GDAL's BAG metadata template (ISO 19115): who, when, what, how.
  const auto now = static_cast<double>(std::time(nullptr));
  const std::string date = format_utc(now, "%Y-%m-%d"), datetime = format_utc(now, "%Y-%m-%dT%H:%M:%S");
  CPLStringList options;
  options.SetNameValue("VAR_ORGANISATION_NAME", metadata.organisation.c_str());
  options.SetNameValue("VAR_INDIVIDUAL_NAME", "bathyslam");
  options.SetNameValue("VAR_POSITION_NAME", "processing software");
  options.SetNameValue("VAR_DATE", date.c_str());
  options.SetNameValue("VAR_DATETIME", datetime.c_str());
  options.SetNameValue("VAR_ABSTRACT", metadata.abstract.c_str());
  options.SetNameValue("VAR_PROCESS_STEP_DESCRIPTION", metadata.process_step.c_str());
  options.SetNameValue("VAR_VERTICAL_UNCERT_CODE", "rawStdDev");
  options.SetNameValue("COMPRESS", "DEFLATE");
  copy_to_file("BAG", path, *mem, options.List(), what);
}

}  // namespace bathyslam
