#include "core/lines/survey_lines.h"

#include <cmath>

namespace bathyslam {
namespace {

constexpr double kDeg = M_PI / 180.0;

double course_deg(const NavSample& from, const NavSample& to) {
  const double c = std::atan2(to.easting - from.easting, to.northing - from.northing) / kDeg;
  return c < 0 ? c + 360.0 : c;
}

double angle_between_deg(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 360.0);
  return d > 180.0 ? 360.0 - d : d;
}

// Distance travelled up to each sample.
std::vector<double> cumulative_distance(const std::vector<NavSample>& nav) {
  std::vector<double> d(nav.size(), 0.0);
  for (std::size_t i = 1; i < nav.size(); ++i) {
    d[i] = d[i - 1] + std::hypot(nav[i].easting - nav[i - 1].easting,
                                 nav[i].northing - nav[i - 1].northing);
  }
  return d;
}

// For each sample: does the course behind it match the course ahead of it?
std::vector<bool> straight_samples(const std::vector<NavSample>& nav,
                                   const std::vector<double>& distance, const LineConfig& config) {
  std::vector<bool> straight(nav.size(), false);
  std::size_t behind = 0, ahead = 0;
  for (std::size_t i = 0; i < nav.size(); ++i) {
    while (distance[i] - distance[behind] > config.course_window_m) ++behind;
    while (ahead + 1 < nav.size() && distance[ahead] - distance[i] < config.course_window_m) ++ahead;
    if (behind == i || ahead == i) continue;  // too close to an end to know
    if (distance[i] - distance[behind] < 0.5 * config.course_window_m ||
        distance[ahead] - distance[i] < 0.5 * config.course_window_m) {
      continue;  // hovering: no course to speak of
    }
    straight[i] = angle_between_deg(course_deg(nav[behind], nav[i]), course_deg(nav[i], nav[ahead])) <=
                  config.max_turn_deg;
  }
  return straight;
}

}  // namespace

std::vector<SurveyLine> split_lines(const std::vector<NavSample>& nav, const LineConfig& config) {
  std::vector<SurveyLine> lines;
  if (nav.size() < 2) return lines;
  const std::vector<double> distance = cumulative_distance(nav);
  const std::vector<bool> straight = straight_samples(nav, distance, config);

  auto close_line = [&](std::size_t first, std::size_t last) {
    const double length = distance[last] - distance[first];
    if (length >= config.min_length_m) {
      lines.push_back({first, last, course_deg(nav[first], nav[last]), length});
    }
  };
  std::size_t i = 0;
  while (i < nav.size()) {
    if (!straight[i]) {
      ++i;
      continue;
    }
    // Grow the run while samples stay straight and on the course the run started with.
    const std::size_t first = i;
    std::size_t reference = first;
    while (reference + 1 < nav.size() && straight[reference + 1] &&
           distance[reference + 1] - distance[first] < config.course_window_m) {
      ++reference;
    }
    const double course = course_deg(nav[first], nav[reference == first ? first + 1 : reference]);
    std::size_t last = first;
    while (last + 1 < nav.size() && straight[last + 1] &&
           (distance[last + 1] - distance[first] < config.course_window_m ||
            angle_between_deg(course_deg(nav[first], nav[last + 1]), course) <=
                config.max_course_spread_deg)) {
      ++last;
    }
    close_line(first, last);
    i = last + 1;
  }
  return lines;
}

}  // namespace bathyslam
