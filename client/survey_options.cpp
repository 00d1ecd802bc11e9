#include "client/survey_options.h"

namespace bathyslam::cli {

SurveyInput SurveyOptions::input() const {
  SurveyInput in;
  in.paths.assign(inputs.begin(), inputs.end());
  in.crs = crs;
  if (!reference_nav.empty()) in.reference_nav = reference_nav;
  return in;
}

void add_survey_options(CLI::App* cmd, SurveyOptions& options) {
  cmd->add_option("survey", options.inputs,
                  "a survey bundle (a folder or a .tar of one), or one or more sonar files of one format in time order (.gsf, Kongsberg EM .all, or XTF from R2Sonic); process: several bundle folders are several surveys of one site, in one graph")
      ->required();
  cmd->add_option("--crs", options.crs, "sonar files: projected CRS of the map frame (default: the data's UTM zone)");
  cmd->add_option("--reference-nav", options.reference_nav, "sonar files: reference navigation in the nav.csv format");
}

}  // namespace bathyslam::cli
