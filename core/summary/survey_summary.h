#pragma once
// What `bathyslam inspect` tells about a survey: counts, time span, extent, lines, and drift
// against the reference navigation when there is one.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/lines/survey_lines.h"
#include "core/submaps/sounding_footprint.h"
#include "core/types/survey.h"

namespace bathyslam {

struct SurveySummary {
  std::string name;
  std::string crs;
  std::size_t nav_samples = 0;
  std::size_t pings = 0;
  std::size_t soundings = 0;
  double time_begin = 0;
  double time_end = 0;
  double easting_min = 0, easting_max = 0;
  double northing_min = 0, northing_max = 0;
  double vehicle_depth_min_m = 0, vehicle_depth_max_m = 0;
  double distance_m = 0;
  std::vector<SurveyLine> lines;

  // Horizontal error of nav against reference_nav at the navigation's times.
  struct Drift {
    double end_m = 0;
    double mean_m = 0;
    double rms_m = 0;
    double max_m = 0;
    double percent_of_distance = 0;  // end error over distance travelled
  };
  std::optional<Drift> drift;

  // How densely the soundings lie (the SLAM core's lengths follow it: length_scale), when the
  // caller measured the pings.
  std::optional<SoundingFootprint> footprint;
};

// `footprint`: the pings' (sounding_footprint), which the summary shows and splits the lines by as
// the pipeline does (line_config_for); without it, the lake's lines.
SurveySummary summarize(const Survey& survey, const std::optional<SoundingFootprint>& footprint = std::nullopt);
nlohmann::json to_json(const SurveySummary& summary);
std::string to_text(const SurveySummary& summary);

}  // namespace bathyslam
