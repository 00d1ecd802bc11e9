#pragma once
// What a user may hand bathyslam as a survey: a bundle (folder or .tar), or one or more GSF
// files in time order with an optional reference navigation CSV.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/io/bundle.h"
#include "core/io/gsf/gsf_survey.h"
#include "core/types/survey.h"

namespace bathyslam {

struct SurveyInput {
  std::vector<std::filesystem::path> paths;
  std::string crs;  // GSF only: the projected CRS; empty: the data's UTM zone
  std::optional<std::filesystem::path> reference_nav;  // GSF only
  bool keep_soundings = true;  // GSF only; false: a survey to summarize (gsf::ReadOptions)
};

struct LoadedSurvey {
  Survey survey;
  std::vector<gsf::FileSummary> gsf_files;  // empty for a bundle
};

// Reads the survey; throws BundleError, gsf::GsfError or std::runtime_error naming the input.
// GSF options given with a bundle, or a bundle given with other paths, are refused.
LoadedSurvey load_survey(const SurveyInput& input);

// The same handing the pings to `sink` (bundle.h) instead of keeping them: the survey comes back
// without pings and beams. A bundle's pings stream from its file, so that its soundings are never
// held whole; GSF files are read whole, then handed on and freed.
LoadedSurvey load_survey(const SurveyInput& input, PingSink& sink);

}  // namespace bathyslam
