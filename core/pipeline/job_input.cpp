#include "core/pipeline/job_input.h"

#include <chrono>
#include <stdexcept>

#include "core/fuse/map_extent.h"
#include "core/fuse/map_resolution.h"
#include "core/pipeline/streamed_survey.h"
#include "core/submaps/joined_surveys.h"

namespace bathyslam {

JobInput read_job_input(const SurveyReader& read, const PipelineConfig& config, FuseConfig fuse) {
  const auto start = std::chrono::steady_clock::now();
  PipelineInputs inputs(config.submaps);
  JobInput job;
  job.survey = read(inputs);
  const PingOutlines& outlines = inputs.outlines();
  if (fuse.resolution_m == 0) fuse.resolution_m = auto_map_resolution(outlines.swept_area(job.survey.nav), fuse.min_soundings);
  if (fuse.max_cells > 0) {
    const MapExtent extent = map_extent(job.survey.nav, outlines.sounding_reach_m(), fuse.resolution_m);
    if (auto problem = map_extent_problem(extent, fuse.resolution_m, fuse.max_cells)) throw std::runtime_error(problem->to_string());
  }
  job.submaps = inputs.take_submaps();
  job.fuse = fuse;
  job.pings = outlines.pings();
  job.read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return job;
}

JobInput read_site_input(const std::vector<SurveyReader>& reads, const std::vector<std::string>& names,
                         const PipelineConfig& config, const FuseConfig& fuse, std::vector<Survey>& surveys) {
  std::vector<SubmapSet> parts;
  JobInput joined;
  for (std::size_t k = 0; k < reads.size(); ++k) {
    JobInput input = read_job_input(reads[k], config, fuse);
    if (!surveys.empty() && input.survey.metadata.crs != surveys.front().metadata.crs) {
      throw std::runtime_error(names.at(k) + ": survey.json: crs " + input.survey.metadata.crs + " is not the first survey's (" +
                               surveys.front().metadata.crs + "): surveys of one site share a CRS");
    }
    if (surveys.empty() || input.fuse.resolution_m < joined.fuse.resolution_m) joined.fuse = input.fuse;
    joined.pings += input.pings;
    joined.read_seconds += input.read_seconds;
    parts.push_back(std::move(input.submaps));
    surveys.push_back(std::move(input.survey));
  }
  joined.submaps = join_surveys(std::move(parts));
  joined.survey = surveys.front();
  return joined;
}

}  // namespace bathyslam
