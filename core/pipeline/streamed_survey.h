#pragma once
// What the pipeline, the map and a survey's summary need of its pings, made as a reader hands
// them on (bundle.h's PingSink), so that the soundings are never held whole
// (docs/performance.md).
#include <optional>
#include <span>
#include <vector>

#include "core/fuse/map_extent.h"
#include "core/fuse/map_resolution.h"
#include "core/io/bundle.h"
#include "core/submaps/submap.h"

namespace bathyslam {

// Each ping's swath (the map's cell size), how far from the vehicle a sounding lands (the map's
// extent), and each ping's time and sounding count (a survey's summary).
class PingOutlines : public PingSink {
 public:
  void begin(const Survey&) override {}
  void ping(double time, std::span<const Beam> beams) override;

  SweptArea swept_area(const std::vector<NavSample>& nav) const;
  SoundingFootprint footprint(const std::vector<NavSample>& nav) const;
  double sounding_reach_m() const { return reach_m_; }
  std::size_t pings() const { return swaths_.size(); }
  // The pings with their sounding counts but no beams to point at, as a survey summarized
  // without its soundings holds them (summarize() counts; nothing may call beams_of()).
  std::vector<Ping> pings_without_beams() const;

 private:
  std::vector<PingSwath> swaths_;
  double reach_m_ = 0;
};

// The submaps beside the outlines: what a job needs.
class PipelineInputs : public PingSink {
 public:
  explicit PipelineInputs(const SubmapConfig& config) : config_(config) {}
  void begin(const Survey& survey) override;
  void ping(double time, std::span<const Beam> beams) override;

  SubmapSet take_submaps();  // once, after the last ping
  const PingOutlines& outlines() const { return outlines_; }

 private:
  SubmapConfig config_;
  std::optional<SubmapBuilder> builder_;
  PingOutlines outlines_;
};

}  // namespace bathyslam
