#include "core/summary/survey_summary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/submaps/submap.h"
#include "core/sync/nav_interpolation.h"

namespace bathyslam {
namespace {

std::optional<SurveySummary::Drift> drift_against(const std::vector<NavSample>& nav,
                                                  const std::vector<NavSample>& reference,
                                                  double distance_m) {
  SurveySummary::Drift drift;
  double sum = 0, sum_sq = 0;
  std::size_t n = 0;
  for (const NavSample& s : nav) {
    const auto truth = interpolate_nav(reference, s.time);
    if (!truth) continue;
    const double e = std::hypot(s.easting - truth->easting, s.northing - truth->northing);
    sum += e;
    sum_sq += e * e;
    drift.max_m = std::max(drift.max_m, e);
    drift.end_m = e;
    ++n;
  }
  if (n == 0) return std::nullopt;
  drift.mean_m = sum / n;
  drift.rms_m = std::sqrt(sum_sq / n);
  drift.percent_of_distance = distance_m > 0 ? 100.0 * drift.end_m / distance_m : 0.0;
  return drift;
}

std::string format(const char* fmt, auto... args) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, fmt, args...);
  return buffer;
}

}  // namespace

SurveySummary summarize(const Survey& survey, const std::optional<SoundingFootprint>& footprint) {
  SurveySummary s;
  s.footprint = footprint;
  s.name = survey.metadata.name;
  s.crs = survey.metadata.crs;
  s.nav_samples = survey.nav.size();
  s.pings = survey.pings.size();
  // Counted from the pings, so that a survey read without its soundings (inspect) counts them too.
  for (const Ping& ping : survey.pings) s.soundings += ping.beam_count;
  if (!survey.nav.empty()) {
    const NavSample& first = survey.nav.front();
    s.time_begin = first.time;
    s.time_end = survey.nav.back().time;
    s.easting_min = s.easting_max = first.easting;
    s.northing_min = s.northing_max = first.northing;
    s.vehicle_depth_min_m = s.vehicle_depth_max_m = first.depth_m;
  }
  for (std::size_t i = 0; i < survey.nav.size(); ++i) {
    const NavSample& n = survey.nav[i];
    s.easting_min = std::min(s.easting_min, n.easting);
    s.easting_max = std::max(s.easting_max, n.easting);
    s.northing_min = std::min(s.northing_min, n.northing);
    s.northing_max = std::max(s.northing_max, n.northing);
    s.vehicle_depth_min_m = std::min(s.vehicle_depth_min_m, n.depth_m);
    s.vehicle_depth_max_m = std::max(s.vehicle_depth_max_m, n.depth_m);
    if (i > 0) {
      s.distance_m += std::hypot(n.easting - survey.nav[i - 1].easting,
                                 n.northing - survey.nav[i - 1].northing);
    }
  }
  if (!survey.pings.empty()) {
    s.time_begin = std::min(s.time_begin, survey.pings.front().time);
    s.time_end = std::max(s.time_end, survey.pings.back().time);
  }
  s.lines = split_lines(survey.nav, line_config_for(footprint.value_or(SoundingFootprint{})));
  if (survey.reference_nav) s.drift = drift_against(survey.nav, *survey.reference_nav, s.distance_m);
  return s;
}

nlohmann::json to_json(const SurveySummary& s) {
  nlohmann::json lines = nlohmann::json::array();
  for (const SurveyLine& l : s.lines) {
    lines.push_back({{"first_nav_index", l.first}, {"last_nav_index", l.last},
                     {"course_deg", l.course_deg}, {"length_m", l.length_m}});
  }
  nlohmann::json j = {
      {"name", s.name},
      {"crs", s.crs},
      {"counts", {{"nav_samples", s.nav_samples}, {"pings", s.pings}, {"soundings", s.soundings}}},
      {"time", {{"begin", s.time_begin}, {"end", s.time_end}, {"duration_s", s.time_end - s.time_begin}}},
      {"extent", {{"easting_min", s.easting_min}, {"easting_max", s.easting_max},
                  {"northing_min", s.northing_min}, {"northing_max", s.northing_max}}},
      {"vehicle_depth_m", {{"min", s.vehicle_depth_min_m}, {"max", s.vehicle_depth_max_m}}},
      {"distance_m", s.distance_m},
      {"line_count", s.lines.size()},
      {"lines", lines},
      {"drift", nullptr}};
  if (s.footprint) {
    j["footprint"] = {{"spacing_m", s.footprint->spacing_m}, {"altitude_m", s.footprint->altitude_m},
                      {"scale", length_scale(*s.footprint)}};
  }
  if (s.drift) {
    j["drift"] = {{"end_m", s.drift->end_m}, {"mean_m", s.drift->mean_m}, {"rms_m", s.drift->rms_m},
                  {"max_m", s.drift->max_m}, {"percent_of_distance", s.drift->percent_of_distance}};
  }
  return j;
}

std::string to_text(const SurveySummary& s) {
  const double duration = s.time_end - s.time_begin;
  std::string out;
  out += format("survey      %s (%s)\n", s.name.c_str(), s.crs.c_str());
  out += format("counts      %zu pings, %zu soundings, %zu navigation samples\n", s.pings,
                s.soundings, s.nav_samples);
  out += format("time        %.3f .. %.3f (%.0f min %.1f s)\n", s.time_begin, s.time_end,
                std::floor(duration / 60.0), std::fmod(duration, 60.0));
  out += format("extent      E %.1f .. %.1f, N %.1f .. %.1f (%.0f m x %.0f m)\n", s.easting_min,
                s.easting_max, s.northing_min, s.northing_max, s.easting_max - s.easting_min,
                s.northing_max - s.northing_min);
  out += format("vehicle     depth %.2f .. %.2f m, %.0f m travelled\n", s.vehicle_depth_min_m,
                s.vehicle_depth_max_m, s.distance_m);
  if (s.footprint) {
    out += format("footprint   soundings %.3g m apart, %.3g m below the sonar: the SLAM core's lengths x %g\n",
                  s.footprint->spacing_m, s.footprint->altitude_m, length_scale(*s.footprint));
  }
  out += format("lines       %zu\n", s.lines.size());
  for (std::size_t i = 0; i < s.lines.size(); ++i) {
    out += format("  line %-3zu  course %5.1f deg, %7.1f m\n", i + 1, s.lines[i].course_deg,
                  s.lines[i].length_m);
  }
  if (s.drift) {
    out += format("drift       %.2f m at the end (%.2f %% of distance), mean %.2f m, rms %.2f m, max %.2f m\n",
                  s.drift->end_m, s.drift->percent_of_distance, s.drift->mean_m, s.drift->rms_m,
                  s.drift->max_m);
  } else {
    out += "drift       no reference navigation\n";
  }
  return out;
}

}  // namespace bathyslam
