#include "core/io/survey_input.h"

#include <algorithm>
#include <stdexcept>

#include "core/io/bundle.h"

namespace bathyslam {

namespace {

// True for GSF files; throws for inputs that are neither GSF files nor a bundle on its own.
bool is_gsf_input(const SurveyInput& input) {
  if (input.paths.empty()) throw std::runtime_error("no survey given");
  if (std::all_of(input.paths.begin(), input.paths.end(), gsf::is_gsf_path)) return true;
  if (input.paths.size() > 1) {
    throw std::runtime_error("several inputs must all be GSF files (.gsf); a bundle comes alone");
  }
  if (!input.crs.empty() || input.reference_nav) {
    throw std::runtime_error(input.paths.front().string() +
                             ": --crs and --reference-nav are for GSF input; a bundle names its CRS in survey.json "
                             "and holds reference_nav.csv");
  }
  return false;
}

LoadedSurvey read_gsf(const SurveyInput& input) {
  gsf::SurveyRead read = gsf::read_survey(input.paths, {input.crs, input.reference_nav, input.keep_soundings});
  return {std::move(read.survey), std::move(read.files)};
}

}  // namespace

LoadedSurvey load_survey(const SurveyInput& input) {
  if (is_gsf_input(input)) return read_gsf(input);
  return {load_bundle(input.paths.front()), {}};
}

LoadedSurvey load_survey(const SurveyInput& input, PingSink& sink) {
  if (!is_gsf_input(input)) {
    BundleReadResult read = stream_bundle(input.paths.front(), sink);
    if (!read.survey) throw BundleError(std::move(read.problems));
    return {std::move(*read.survey), {}};
  }
  // GSF holds the navigation in the pings: a first reading without the soundings gives it (and
  // every error), a second hands the soundings on.
  SurveyInput navigation_only = input;
  navigation_only.keep_soundings = false;
  LoadedSurvey loaded = read_gsf(navigation_only);
  gsf::stream_soundings(input.paths, loaded.survey, sink);
  return loaded;
}

}  // namespace bathyslam
