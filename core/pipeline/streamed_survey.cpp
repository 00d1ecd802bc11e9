#include "core/pipeline/streamed_survey.h"

#include <algorithm>

namespace bathyslam {

void PipelineInputs::begin(const Survey& survey) { builder_.emplace(survey.nav, survey.reference_nav, config_); }

void PipelineInputs::ping(double time, std::span<const Beam> beams) {
  builder_->add_ping(time, beams);
  swaths_.push_back(ping_swath(time, beams));
  reach_m_ = std::max(reach_m_, bathyslam::sounding_reach_m(beams));
}

SubmapSet PipelineInputs::take_submaps() { return builder_ ? builder_->finish() : SubmapSet{}; }

SweptArea PipelineInputs::swept_area(const std::vector<NavSample>& nav) const {
  return bathyslam::swept_area(nav, swaths_);
}

}  // namespace bathyslam
