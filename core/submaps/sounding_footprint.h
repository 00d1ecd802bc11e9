#pragma once
// How densely a survey's soundings cover the seabed, and from how high: the map's cell size
// (fuse/map_resolution.h) and the SLAM core's lengths (pipeline/parameters.h,
// scaled_to_footprint) follow it.
#include <cstdint>
#include <span>
#include <vector>

#include "core/types/survey.h"

namespace bathyslam {

struct SweptArea {
  double track_m = 0;        // distance sailed while pinging (see robust_track_length)
  double swath_m = 0;        // median across-track width of a ping
  double soundings = 0;
  double density_per_m2() const;  // 0 when nothing was swept
};

// What the swept area needs of a ping, for a reader that does not keep the beams.
struct PingSwath {
  double time = 0;
  double width_m = 0;  // across track, from its leftmost to its rightmost beam
  std::uint32_t soundings = 0;
  double down_m = 0;   // the median height of its soundings below the sonar
};
PingSwath ping_swath(double time, std::span<const Beam> beams);

SweptArea swept_area(const std::vector<NavSample>& nav, const std::vector<PingSwath>& pings);
SweptArea swept_area(const Survey& survey);
std::vector<PingSwath> ping_swaths(const Survey& survey);

struct SoundingFootprint {
  // The seabed area per sounding as a length, 1 / sqrt(soundings per m² swept): soundings 0.1 m
  // apart across track and 0.2 m along give 0.14 m. 0 when nothing was swept.
  double spacing_m = 0;
  double altitude_m = 0;  // the median over pings of their soundings' median height below the sonar
};
SoundingFootprint sounding_footprint(const std::vector<NavSample>& nav, const std::vector<PingSwath>& pings);
SoundingFootprint sounding_footprint(const Survey& survey);

// The sounding spacing of the survey Table 1's lengths are for: 512 beams over 140° from 9 m above
// the bed (0.1 m apart across track on average) at 2 m/s and 10 pings a second (0.2 m along), as
// the paper's lake and our `lake` scenario.
inline constexpr double kPaperSpacingM = 0.14;

// How many times the lake's lengths a survey of this footprint needs: the power of two nearest its
// spacing over kPaperSpacingM (an octave: the lake's spacing varies by a few percent between
// surveys, and Table 1 must stay exact there); 1 when nothing was swept.
double length_scale(const SoundingFootprint& footprint);

}  // namespace bathyslam
