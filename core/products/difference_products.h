#pragma once
// The difference of two surveys of a site as files: difference_<a>_<b>.tif (Float32 bands change,
// sigma, significant and the local offset taken out, NaN where either survey has no data) and difference_<a>_<b>.json (the
// registration's sigmas, the counts and the changed areas in the CRS), numbered from 1 in the
// order the surveys were joined.
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "core/fuse/difference.h"
#include "core/pipeline/pipeline.h"
#include "core/types/survey.h"

namespace bathyslam {

struct DifferenceProducts {
  std::string stem;  // difference_<a>_<b>; no file written when the surveys share no cell
  DifferenceMap map;
  nlohmann::json summary;  // what <stem>.json holds; its "file" is null when no file was written
};

// The change from survey `before` to survey `after` (0-based) of the result's joined surveys.
DifferenceProducts write_difference_products(const PipelineResult& result, const SurveyMetadata& survey,
                                             const FuseConfig& fuse, int before, int after,
                                             const DifferenceConfig& config, const std::filesystem::path& dir);

}  // namespace bathyslam
