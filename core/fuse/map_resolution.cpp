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
double robust_track_length(const Survey& survey) {
  std::vector<double> intervals, steps;
  std::optional<NavSample> previous;
  double previous_time = 0;
  for (const Ping& ping : survey.pings) {
    const std::optional<NavSample> here = interpolate_nav(survey.nav, ping.time);
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

SweptArea swept_area(const Survey& survey) {
  SweptArea swept;
  if (survey.pings.empty()) return swept;
  std::vector<double> widths;
  widths.reserve(survey.pings.size());
  for (const Ping& ping : survey.pings) {
    const auto beams = survey.beams_of(ping);
    if (beams.empty()) continue;
    const auto [left, right] =
        std::minmax_element(beams.begin(), beams.end(), [](const Beam& a, const Beam& b) { return a.across < b.across; });
    widths.push_back(double{right->across} - double{left->across});
    swept.soundings += static_cast<double>(beams.size());
  }
  if (widths.empty()) return swept;
  swept.swath_m = median(std::move(widths));
  swept.track_m = robust_track_length(survey);
  return swept;
}

double auto_map_resolution(const Survey& survey, int min_soundings, double finest_m) {
  const double density = swept_area(survey).density_per_m2();
  if (!(density > 0)) return finest_m;
  const double cell_area = 2.0 * std::max(min_soundings, 1) / density;
  double resolution = finest_m;
  while (resolution * resolution < cell_area && resolution < 1e4) resolution *= 2;
  return resolution;
}

}  // namespace bathyslam
