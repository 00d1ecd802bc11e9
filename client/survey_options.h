#pragma once
// The survey a command reads: a bundle, or sonar files (GSF, EM .all) with their CRS and
// reference navigation.
// Shared by every command that takes one, so they all accept the same inputs.
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "core/io/survey_input.h"

namespace bathyslam::cli {

struct SurveyOptions {
  std::vector<std::string> inputs;
  std::string crs;
  std::string reference_nav;

  SurveyInput input() const;
};

// Adds the positional `survey` and --crs, --reference-nav to `cmd`.
void add_survey_options(CLI::App* cmd, SurveyOptions& options);

}  // namespace bathyslam::cli
