#include "core/fuse/map_resolution.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "core/sync/nav_interpolation.h"

namespace bathyslam {

namespace {

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

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

SweptArea swept_area(const Survey& survey) {
  std::vector<PingSwath> pings;
  pings.reserve(survey.pings.size());
  for (const Ping& ping : survey.pings) pings.push_back(ping_swath(ping.time, survey.beams_of(ping)));
  return swept_area(survey.nav, pings);
}

double auto_map_resolution(const SweptArea& swept, int min_soundings, double finest_m) {
  const double density = swept.density_per_m2();
  if (!(density > 0)) return finest_m;
  const double cell_area = 2.0 * std::max(min_soundings, 1) / density;
  double resolution = finest_m;
  while (resolution * resolution < cell_area && resolution < 1e4) resolution *= 2;
  return resolution;
}

double auto_map_resolution(const Survey& survey, int min_soundings, double finest_m) {
  return auto_map_resolution(swept_area(survey), min_soundings, finest_m);
}

}  // namespace bathyslam
