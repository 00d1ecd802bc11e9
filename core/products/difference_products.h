#pragma once
// The difference of two surveys of a site as files: difference_<a>_<b>.tif (Float32 bands change,
// sigma, significant and the local offset taken out, NaN where either survey has no data) and difference_<a>_<b>.json (the
// registration's sigmas, the counts and the changed areas in the CRS), numbered from 1 in the
// order the surveys were joined.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

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

// Up to this many surveys a job makes the difference of every pair; beyond, 20 surveys would
// make 190: each later survey's from the first and from the one before it.
inline constexpr int kAllDifferencesUpTo = 5;

// The pairs (before, after), 0-based, before < after, whose differences a job of `surveys` makes,
// ordered by before, then after.
std::vector<std::pair<int, int>> difference_pairs(int surveys);

// The change from survey `before` to survey `after` (0-based) of the result's joined surveys.
DifferenceProducts write_difference_products(const PipelineResult& result, const SurveyMetadata& survey,
                                             const FuseConfig& fuse, int before, int after,
                                             const DifferenceConfig& config, const std::filesystem::path& dir);

}  // namespace bathyslam
