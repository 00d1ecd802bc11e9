#pragma once
// The survey's navigation with the pipeline's correction applied: what a hydrographer merges
// back into the sonar data.
#include <vector>

#include "core/pipeline/pipeline.h"

namespace bathyslam {

// Every DR sample moved by its submaps' correction (interpolated between submap middles), in
// the nav.csv columns.
std::vector<NavSample> corrected_navigation(const Survey& survey, const PipelineResult& result);

}  // namespace bathyslam
