#include "core/io/survey_input.h"

#include <algorithm>
#include <stdexcept>

#include "core/io/bundle.h"

namespace bathyslam {

LoadedSurvey load_survey(const SurveyInput& input) {
  if (input.paths.empty()) throw std::runtime_error("no survey given");
  const bool all_gsf = std::all_of(input.paths.begin(), input.paths.end(), gsf::is_gsf_path);
  if (all_gsf) {
    gsf::SurveyRead read = gsf::read_survey(input.paths, {input.crs, input.reference_nav, input.keep_soundings});
    return {std::move(read.survey), std::move(read.files)};
  }
  if (input.paths.size() > 1) {
    throw std::runtime_error("several inputs must all be GSF files (.gsf); a bundle comes alone");
  }
  if (!input.crs.empty() || input.reference_nav) {
    throw std::runtime_error(input.paths.front().string() +
                             ": --crs and --reference-nav are for GSF input; a bundle names its CRS in survey.json "
                             "and holds reference_nav.csv");
  }
  return {load_bundle(input.paths.front()), {}};
}

}  // namespace bathyslam
