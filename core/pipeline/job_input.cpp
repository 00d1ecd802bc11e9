#include "core/pipeline/job_input.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "core/fuse/map_extent.h"
#include "core/fuse/map_resolution.h"
#include "core/pipeline/ping_handoff.h"
#include "core/pipeline/streamed_survey.h"
#include "core/submaps/joined_surveys.h"

namespace bathyslam {

JobInput read_job_input(const SurveyReader& read, const PipelineConfig& config, FuseConfig fuse) {
  const auto start = std::chrono::steady_clock::now();
  PipelineInputs inputs(config.submaps);
  JobInput job;
  if (plan_of(config).threads > 1) {
    PingHandoff handoff(inputs);
    job.survey = read(handoff);
    handoff.finish();
  } else {
    job.survey = read(inputs);
  }
  const PingOutlines& outlines = inputs.outlines();
  if (fuse.resolution_m == 0) fuse.resolution_m = auto_map_resolution(outlines.swept_area(job.survey.nav), fuse.min_soundings);
  if (fuse.max_cells > 0) {
    const MapExtent extent = map_extent(job.survey.nav, outlines.sounding_reach_m(), fuse.resolution_m);
    if (auto problem = map_extent_problem(extent, fuse.resolution_m, fuse.max_cells)) throw std::runtime_error(problem->to_string());
  }
  job.submaps = inputs.take_submaps();
  job.sounding_reach_m = outlines.sounding_reach_m();
  job.fuse = fuse;
  job.pings = outlines.pings();
  job.read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return job;
}

JobInput read_site_input(const std::vector<SurveyReader>& reads, const std::vector<std::string>& names,
                         const PipelineConfig& config, const FuseConfig& fuse, std::vector<Survey>& surveys) {
  std::vector<SubmapSet> parts;
  JobInput joined;
  std::vector<NavSample> all_nav;  // every survey's, for the joined map's extent
  double reach_m = 0;
  for (std::size_t k = 0; k < reads.size(); ++k) {
    // A reader's own errors pass as they are (the service tells an outage from bad input by type);
    // they name the files they read.
    JobInput input = read_job_input(reads[k], config, fuse);
    if (!surveys.empty() && input.survey.metadata.crs != surveys.front().metadata.crs) {
      throw std::runtime_error(names.at(k) + ": survey.json: crs " + input.survey.metadata.crs + " is not the first survey's (" +
                               surveys.front().metadata.crs + "): surveys of one site share a CRS");
    }
    if (surveys.empty() || input.fuse.resolution_m < joined.fuse.resolution_m) joined.fuse = input.fuse;
    joined.pings += input.pings;
    joined.read_seconds += input.read_seconds;
    all_nav.insert(all_nav.end(), input.survey.nav.begin(), input.survey.nav.end());
    reach_m = std::max(reach_m, input.sounding_reach_m);
    parts.push_back(std::move(input.submaps));
    surveys.push_back(std::move(input.survey));
  }
  // Each survey passed alone at its own cell; the joined map has the finest cell over all of them.
  if (fuse.max_cells > 0) {
    const MapExtent extent = map_extent(all_nav, reach_m, joined.fuse.resolution_m);
    if (auto problem = map_extent_problem(extent, joined.fuse.resolution_m, fuse.max_cells))
      throw std::runtime_error("the surveys together: " + problem->to_string());
  }
  joined.submaps = join_surveys(std::move(parts));
  joined.survey = surveys.front();
  return joined;
}

}  // namespace bathyslam
