#include "core/io/survey_input.h"

#include <algorithm>
#include <cctype>
#include <limits>
#include <stdexcept>

#include "core/io/bundle.h"

namespace bathyslam {

namespace {

enum class InputKind { kBundle, kGsf, kAll, kXtf };

// What the inputs are; throws for inputs that are neither sonar files of one format nor a bundle
// on its own.
InputKind kind_of(const SurveyInput& input) {
  if (input.paths.empty()) throw std::runtime_error("no survey given");
  if (std::all_of(input.paths.begin(), input.paths.end(), gsf::is_gsf_path)) return InputKind::kGsf;
  if (std::all_of(input.paths.begin(), input.paths.end(), kongsberg::is_all_path)) return InputKind::kAll;
  if (std::all_of(input.paths.begin(), input.paths.end(), xtf::is_xtf_path)) return InputKind::kXtf;
  if (std::any_of(input.paths.begin(), input.paths.end(), is_sonar_file_path) && input.paths.size() > 1) {
    throw std::runtime_error("sonar files of one survey must be of one format (all .gsf, all .all or all .xtf)");
  }
  if (input.paths.size() > 1) {
    throw std::runtime_error("several inputs must all be sonar files (.gsf, .all or .xtf); a bundle comes alone");
  }
  if (!input.crs.empty() || input.reference_nav) {
    throw std::runtime_error(input.paths.front().string() +
                             ": --crs and --reference-nav are for sonar files; a bundle names its CRS in survey.json "
                             "and holds reference_nav.csv");
  }
  return InputKind::kBundle;
}

LoadedSurvey read_sonar_files(InputKind kind, const SurveyInput& input) {
  LoadedSurvey loaded;
  if (kind == InputKind::kGsf) {
    gsf::SurveyRead read = gsf::read_survey(input.paths, {input.crs, input.reference_nav, input.keep_soundings});
    loaded.survey = std::move(read.survey);
    loaded.gsf_files = std::move(read.files);
  } else if (kind == InputKind::kAll) {
    kongsberg::SurveyRead read = kongsberg::read_survey(input.paths, {input.crs, input.reference_nav, input.keep_soundings});
    loaded.survey = std::move(read.survey);
    loaded.all_files = std::move(read.files);
  } else {
    xtf::SurveyRead read = xtf::read_survey(input.paths, {input.crs, input.reference_nav, input.keep_soundings});
    loaded.survey = std::move(read.survey);
    loaded.xtf_files = std::move(read.files);
  }
  return loaded;
}

// kind_of for callers that take sonar files only: a bundle is refused naming it.
InputKind sonar_kind_of(const SurveyInput& input) {
  const InputKind kind = kind_of(input);
  if (kind == InputKind::kBundle) throw std::runtime_error(input.paths.front().string() + ": not a sonar file (.gsf, .all, .xtf)");
  return kind;
}

}  // namespace

bool is_sonar_file_path(const std::filesystem::path& path) {
  return gsf::is_gsf_path(path) || kongsberg::is_all_path(path) || xtf::is_xtf_path(path);
}

LoadedSurvey load_survey(const SurveyInput& input) {
  const InputKind kind = kind_of(input);
  if (kind != InputKind::kBundle) return read_sonar_files(kind, input);
  return {load_bundle(input.paths.front()), {}, {}, {}};
}

LoadedSurvey load_survey(const SurveyInput& input, PingSink& sink) {
  if (kind_of(input) == InputKind::kBundle) {
    BundleReadResult read = stream_bundle(input.paths.front(), sink);
    if (!read.survey) throw BundleError(std::move(read.problems));
    return {std::move(*read.survey), {}, {}, {}};
  }
  // Sonar files hold the navigation in the pings (or beside them): a first reading without the
  // soundings gives it (and every error), a second hands the soundings on.
  LoadedSurvey loaded = read_sonar_navigation(input);
  stream_sonar_soundings(input, loaded.survey, sink);
  return loaded;
}

LoadedSurvey read_sonar_navigation(const SurveyInput& input) {
  const InputKind kind = sonar_kind_of(input);
  SurveyInput navigation_only = input;
  navigation_only.keep_soundings = false;
  return read_sonar_files(kind, navigation_only);
}

void stream_sonar_soundings(const SurveyInput& input, Survey& survey, PingSink& sink) {
  switch (sonar_kind_of(input)) {
    case InputKind::kGsf: return gsf::stream_soundings(input.paths, survey, sink);
    case InputKind::kAll: return kongsberg::stream_soundings(input.paths, survey, sink);
    default: return xtf::stream_soundings(input.paths, survey, sink);
  }
}

bool is_sonar_file_name(const std::string& name) {
  if (name.empty() || name.size() > 200 || name.front() == '.' || !is_sonar_file_path(name)) return false;
  return std::all_of(name.begin(), name.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '.' || c == '_' || c == '-';
  });
}

std::vector<std::filesystem::path> sonar_files_in_time_order(std::vector<std::filesystem::path> files) {
  const InputKind kind = sonar_kind_of(SurveyInput{files, "", std::nullopt, false});
  // Files without a ping go last, by name.
  std::vector<std::pair<double, std::filesystem::path>> timed;
  for (std::filesystem::path& path : files) {
    const std::optional<double> first = kind == InputKind::kGsf   ? gsf::first_ping_time(path)
                                        : kind == InputKind::kAll ? kongsberg::first_swath_time(path)
                                                                  : xtf::first_ping_time(path);
    timed.emplace_back(first.value_or(std::numeric_limits<double>::infinity()), std::move(path));
  }
  std::sort(timed.begin(), timed.end());
  std::vector<std::filesystem::path> ordered;
  for (auto& [time, path] : timed) ordered.push_back(std::move(path));
  return ordered;
}

}  // namespace bathyslam
