#pragma once
// The survey's navigation with the pipeline's correction applied: what a hydrographer merges
// back into the sonar data.
#include <vector>

#include "core/pipeline/pipeline.h"

namespace bathyslam {

// Every DR sample moved by its submaps' correction (interpolated between submap middles), in
// the nav.csv columns. `survey` is the result's `survey_index`-th survey (join_surveys; 0 when
// it is alone).
std::vector<NavSample> corrected_navigation(const Survey& survey, const PipelineResult& result, int survey_index = 0);

}  // namespace bathyslam
