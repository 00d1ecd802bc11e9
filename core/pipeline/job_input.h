#pragma once
// The first half of a job, the same offline (`bathyslam process`) and in the service's
// scheduler: the survey read with its pings streamed straight into submaps (the soundings are
// never held whole: docs/performance.md), the map's cell size chosen from the soundings'
// density, and its extent checked before any work. Then run_pipeline, and the products, whose
// destination (files, the database) is the caller's.
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "core/fuse/fuse.h"
#include "core/io/bundle.h"
#include "core/pipeline/pipeline_config.h"
#include "core/submaps/submap.h"

namespace bathyslam {

struct JobInput {
  Survey survey;  // without its soundings
  SubmapSet submaps;
  FuseConfig fuse;  // with its cell size chosen
  std::size_t pings = 0;
  double read_seconds = 0;  // the "submaps" stage's time (run_pipeline)
  double sounding_reach_m = 0;  // how far from the vehicle a sounding landed (the map's extent)
};

// Streams a survey's pings into the sink it is given and returns the survey; throws naming the
// input when it cannot.
using SurveyReader = std::function<Survey(PingSink&)>;

// `fuse.resolution_m` 0: the cell size from the soundings' density (auto_map_resolution). With
// `fuse.max_cells` > 0, a map that would need more cells is refused here, naming nav.csv's
// extent (std::runtime_error), before the pipeline spends anything on it.
JobInput read_job_input(const SurveyReader& read, const PipelineConfig& config, FuseConfig fuse);

// Several surveys of one site: each read as read_job_input reads one, their submaps joined in
// the order given (join_surveys), the map's cell the finest any of them asks for; `surveys`
// receives each survey without its soundings, and the input's `survey` is the first's. Throws
// std::runtime_error naming `names[k]` when survey k's CRS is not the first's, and when the
// surveys' joined map would exceed `fuse.max_cells`.
JobInput read_site_input(const std::vector<SurveyReader>& reads, const std::vector<std::string>& names,
                         const PipelineConfig& config, const FuseConfig& fuse, std::vector<Survey>& surveys);

}  // namespace bathyslam
