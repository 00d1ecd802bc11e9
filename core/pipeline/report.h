#pragma once
// The quality report of a pipeline run: JSON for machines, a few lines for people, PNG plots.
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "core/pipeline/pipeline.h"

namespace bathyslam {

nlohmann::json report_json(const PipelineResult& result);
std::string report_summary(const PipelineResult& result);
// consistency_histogram.png, trajectory_error.png, trajectory.png into `dir`.
void write_report_plots(const PipelineResult& result, const std::filesystem::path& dir);

}  // namespace bathyslam
