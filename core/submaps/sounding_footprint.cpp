#include "core/submaps/sounding_footprint.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/sync/nav_interpolation.h"
#include "core/types/median.h"

namespace bathyslam {

namespace {

// The distance sailed while pinging: the median step between consecutive pings times the number
// of steps, leaving out pauses (steps of more than 10 median ping intervals). Medians, so that a
// stray position fix hundreds of km away, or the gap between two files far apart, neither
// lengthens the track nor coarsens the cells (the extent check must still see such a survey).
double robust_track_length(const std::vector<NavSample>& nav, const std::vector<PingSwath>& pings) {
  std::vector<double> intervals, steps;
  std::optional<NavSample> previous;
  double previous_time = 0;
  for (const PingSwath& ping : pings) {
    const std::optional<NavSample> here = interpolate_nav(nav, ping.time);
    if (!here) continue;
    if (previous) {
      intervals.push_back(ping.time - previous_time);
      steps.push_back(std::hypot(here->easting - previous->easting, here->northing - previous->northing));
    }
    previous = here;
    previous_time = ping.time;
  }
  const double usual_interval = median(intervals);
  const auto sailing = std::count_if(intervals.begin(), intervals.end(),
                                     [&](double interval) { return interval <= 10 * usual_interval; });
  return median(steps) * static_cast<double>(sailing);
}

}  // namespace

double SweptArea::density_per_m2() const {
  const double area = track_m * swath_m;
  return area > 0 ? soundings / area : 0;
}

PingSwath ping_swath(double time, std::span<const Beam> beams) {
  PingSwath swath{time, 0, static_cast<std::uint32_t>(beams.size())};
  if (beams.empty()) return swath;
  const auto [left, right] =
      std::minmax_element(beams.begin(), beams.end(), [](const Beam& a, const Beam& b) { return a.across < b.across; });
  swath.width_m = double{right->across} - double{left->across};
  std::vector<double> down;
  down.reserve(beams.size());
  for (const Beam& b : beams) down.push_back(b.down);
  swath.down_m = median(std::move(down));
  return swath;
}

SweptArea swept_area(const std::vector<NavSample>& nav, const std::vector<PingSwath>& pings) {
  SweptArea swept;
  std::vector<double> widths;
  widths.reserve(pings.size());
  for (const PingSwath& ping : pings) {
    if (ping.soundings == 0) continue;
    widths.push_back(ping.width_m);
    swept.soundings += ping.soundings;
  }
  if (widths.empty()) return swept;
  swept.swath_m = median(std::move(widths));
  swept.track_m = robust_track_length(nav, pings);
  return swept;
}

std::vector<PingSwath> ping_swaths(const Survey& survey) {
  std::vector<PingSwath> pings;
  pings.reserve(survey.pings.size());
  for (const Ping& ping : survey.pings) pings.push_back(ping_swath(ping.time, survey.beams_of(ping)));
  return pings;
}

SweptArea swept_area(const Survey& survey) { return swept_area(survey.nav, ping_swaths(survey)); }

SoundingFootprint sounding_footprint(const std::vector<NavSample>& nav, const std::vector<PingSwath>& pings) {
  const double density = swept_area(nav, pings).density_per_m2();
  std::vector<double> down;
  down.reserve(pings.size());
  for (const PingSwath& ping : pings) {
    if (ping.soundings > 0) down.push_back(ping.down_m);
  }
  return {density > 0 ? 1 / std::sqrt(density) : 0, median(std::move(down))};
}

SoundingFootprint sounding_footprint(const Survey& survey) { return sounding_footprint(survey.nav, ping_swaths(survey)); }

double length_scale(const SoundingFootprint& footprint) {
  if (footprint.spacing_m <= 0) return 1;
  return std::exp2(std::round(std::log2(footprint.spacing_m / kPaperSpacingM)));
}

}  // namespace bathyslam
