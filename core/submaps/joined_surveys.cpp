#include "core/submaps/joined_surveys.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace bathyslam {

SubmapSet join_surveys(std::vector<SubmapSet> surveys) {
  if (surveys.empty()) throw std::invalid_argument("no surveys to join");
  SubmapSet joined;
  joined.origin = surveys.front().origin;
  for (std::size_t k = 0; k < surveys.size(); ++k) {
    SubmapSet& survey = surveys[k];
    if (survey.submaps.empty()) throw std::invalid_argument("survey " + std::to_string(k + 1) + " has no submaps");
    const Eigen::Vector3d shift(survey.origin.easting - joined.origin.easting, survey.origin.northing - joined.origin.northing, 0);
    const int line_offset = static_cast<int>(joined.lines.size());
    if (k > 0) joined.survey_starts.push_back(static_cast<int>(joined.submaps.size()));
    for (Submap& s : survey.submaps) {
      s.index = static_cast<int>(joined.submaps.size());
      if (s.line >= 0) s.line += line_offset;
      s.dr_pose.pretranslate(shift);
      if (s.reference_pose) s.reference_pose->pretranslate(shift);
      joined.submaps.push_back(std::move(s));
    }
    joined.lines.insert(joined.lines.end(), survey.lines.begin(), survey.lines.end());
    joined.pings_dropped += survey.pings_dropped;
    if (survey.footprint.spacing_m > joined.footprint.spacing_m) joined.footprint = survey.footprint;
  }
  return joined;
}

int survey_of_submap(const SubmapSet& set, int index) { return survey_of(set.survey_starts, index); }

NodeRange survey_submaps(const SubmapSet& set, int survey) {
  return survey_nodes(set.survey_starts, survey, static_cast<int>(set.submaps.size()));
}

}  // namespace bathyslam
