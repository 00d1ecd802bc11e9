#include "core/pipeline/streamed_survey.h"

#include <algorithm>

namespace bathyslam {

void PingOutlines::ping(double time, std::span<const Beam> beams) {
  swaths_.push_back(ping_swath(time, beams));
  reach_m_ = std::max(reach_m_, bathyslam::sounding_reach_m(beams));
}

SweptArea PingOutlines::swept_area(const std::vector<NavSample>& nav) const {
  return bathyslam::swept_area(nav, swaths_);
}

SoundingFootprint PingOutlines::footprint(const std::vector<NavSample>& nav) const {
  return sounding_footprint(nav, swaths_);
}

std::vector<Ping> PingOutlines::pings_without_beams() const {
  std::vector<Ping> pings;
  pings.reserve(swaths_.size());
  for (const PingSwath& swath : swaths_) pings.push_back({swath.time, 0, swath.soundings});
  return pings;
}

void PipelineInputs::begin(const Survey& survey) { builder_.emplace(survey.nav, survey.reference_nav, config_); }

void PipelineInputs::ping(double time, std::span<const Beam> beams) {
  builder_->add_ping(time, beams);
  outlines_.ping(time, beams);
}

SubmapSet PipelineInputs::take_submaps() { return builder_ ? builder_->finish() : SubmapSet{}; }

}  // namespace bathyslam
