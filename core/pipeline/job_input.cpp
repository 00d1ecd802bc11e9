#include "core/pipeline/job_input.h"

#include <chrono>
#include <stdexcept>

#include "core/fuse/map_extent.h"
#include "core/fuse/map_resolution.h"
#include "core/pipeline/streamed_survey.h"

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

}  // namespace bathyslam
