#pragma once
// What a user may hand bathyslam as a survey: a bundle (folder or .tar), or one or more sonar
// files of one format (GSF, Kongsberg EM .all or XTF) in time order with an optional reference
// navigation CSV.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/io/bundle.h"
#include "core/io/gsf/gsf_survey.h"
#include "core/io/kongsberg/all_survey.h"
#include "core/io/xtf/xtf_survey.h"
#include "core/types/survey.h"

namespace bathyslam {

struct SurveyInput {
  std::vector<std::filesystem::path> paths;
  std::string crs;  // sonar files only: the projected CRS; empty: the data's UTM zone
  std::optional<std::filesystem::path> reference_nav;  // sonar files only
  bool keep_soundings = true;  // sonar files only; false: a survey to summarize (gsf::ReadOptions)
};

struct LoadedSurvey {
  Survey survey;
  std::vector<gsf::FileSummary> gsf_files;  // empty but for GSF input
  std::vector<kongsberg::FileSummary> all_files;  // empty but for .all input
  std::vector<xtf::FileSummary> xtf_files;        // empty but for XTF input
};

// Whether `path` names a sonar file bathyslam reads (GSF, .all or .xtf), by its extension.
bool is_sonar_file_path(const std::filesystem::path& path);

// Whether `name` may name an uploaded sonar file: a plain file name ending in .gsf, .all or .xtf, of
// letters, digits, '.', '_' and '-', not starting with '.', at most 200 characters (it becomes a
// path on the server).
bool is_sonar_file_name(const std::string& name);

// Sonar files of one format ordered by their first ping's time, for files whose order nobody gave
// (a service upload).
std::vector<std::filesystem::path> sonar_files_in_time_order(std::vector<std::filesystem::path> files);

// The two readings load_survey(input, sink) makes of sonar files, for a caller that changes the
// survey in between (the service names it as it was uploaded): the navigation and every error
// (the survey without soundings), then the soundings handed to `sink`, the survey's pings freed.
LoadedSurvey read_sonar_navigation(const SurveyInput& input);
void stream_sonar_soundings(const SurveyInput& input, Survey& survey, PingSink& sink);

// Reads the survey; throws BundleError, gsf::GsfError, kongsberg::AllError, xtf::XtfError or std::runtime_error
// naming the input. Sonar-file options given with a bundle, a bundle given with other paths, and
// files of two formats are refused.
LoadedSurvey load_survey(const SurveyInput& input);

// The same handing the pings to `sink` (bundle.h) instead of keeping them: the survey comes back
// without pings and beams. A bundle's pings stream from its file; sonar files are read twice,
// first for the navigation, then ping by ping: the soundings are never held whole.
LoadedSurvey load_survey(const SurveyInput& input, PingSink& sink);

}  // namespace bathyslam
