#pragma once
// What the pipeline and the map need of a survey's pings, made as a reader hands them on
// (bundle.h's PingSink), so that the soundings are never held whole (README "Performance"): the
// submaps, each ping's swath (the map's cell size) and how far from the vehicle a sounding lands
// (the map's extent).
#include <optional>
#include <span>
#include <vector>

#include "core/fuse/map_extent.h"
#include "core/fuse/map_resolution.h"
#include "core/io/bundle.h"
#include "core/submaps/submap.h"

namespace bathyslam {

class PipelineInputs : public PingSink {
 public:
  explicit PipelineInputs(const SubmapConfig& config) : config_(config) {}
  void begin(const Survey& survey) override;
  void ping(double time, std::span<const Beam> beams) override;

  SubmapSet take_submaps();  // once, after the last ping
  SweptArea swept_area(const std::vector<NavSample>& nav) const;
  double sounding_reach_m() const { return reach_m_; }
  std::size_t pings() const { return swaths_.size(); }

 private:
  SubmapConfig config_;
  std::optional<SubmapBuilder> builder_;
  std::vector<PingSwath> swaths_;
  double reach_m_ = 0;
};

}  // namespace bathyslam
