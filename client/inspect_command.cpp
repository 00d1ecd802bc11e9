#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "client/commands.h"
#include "client/survey_options.h"
#include "core/io/bundle.h"
#include "core/io/survey_input.h"
#include "core/pipeline/streamed_survey.h"
#include "core/summary/survey_summary.h"

namespace bathyslam::cli {
namespace {

struct InspectOptions {
  SurveyOptions survey;
  bool json = false;
};

void inspect_bundle(const std::string& bundle, bool json) {
  BundleReadResult result = read_bundle(bundle);
  for (const Problem& p : result.problems) {
    if (p.file.empty()) std::fprintf(stderr, "%s\n", p.to_string().c_str());
    else std::fprintf(stderr, "%s/%s\n", bundle.c_str(), p.to_string().c_str());
  }
  if (!result.survey) throw std::runtime_error(bundle + ": not a valid survey bundle");
  const SurveySummary summary = summarize(*result.survey, sounding_footprint(*result.survey));
  if (json) std::printf("%s\n", to_json(summary).dump(2).c_str());
  else std::printf("%s", to_text(summary).c_str());
}

// Sonar files: what each file holds (pings, rejected beams, records or datagrams), then the
// survey bathyslam makes of them, its pings outlined as they are read (memory: the navigation and
// each ping's outline, not the beams).
void inspect_sonar_files(const InspectOptions& o) {
  PingOutlines outlines;
  LoadedSurvey loaded = load_survey(o.survey.input(), outlines);
  loaded.survey.pings = outlines.pings_without_beams();
  const SurveySummary summary = summarize(loaded.survey, outlines.footprint(loaded.survey.nav));
  if (o.json) {
    nlohmann::json files = nlohmann::json::array();
    for (const gsf::FileSummary& f : loaded.gsf_files) files.push_back(gsf::to_json(f));
    for (const kongsberg::FileSummary& f : loaded.all_files) files.push_back(kongsberg::to_json(f));
    for (const xtf::FileSummary& f : loaded.xtf_files) files.push_back(xtf::to_json(f));
    const char* key = !loaded.all_files.empty() ? "all_files" : !loaded.xtf_files.empty() ? "xtf_files" : "gsf_files";
    std::printf("%s\n", nlohmann::json{{key, files}, {"survey", to_json(summary)}}.dump(2).c_str());
    return;
  }
  for (const gsf::FileSummary& f : loaded.gsf_files) std::printf("%s", gsf::to_text(f).c_str());
  for (const kongsberg::FileSummary& f : loaded.all_files) std::printf("%s", kongsberg::to_text(f).c_str());
  for (const xtf::FileSummary& f : loaded.xtf_files) std::printf("%s", xtf::to_text(f).c_str());
  std::printf("%s", to_text(summary).c_str());
}

void run_inspect(const InspectOptions& o) {
  const std::vector<std::string>& inputs = o.survey.inputs;
  if (inputs.size() == 1 && !is_sonar_file_path(inputs.front())) {
    if (!o.survey.crs.empty() || !o.survey.reference_nav.empty()) {
      throw std::runtime_error("--crs and --reference-nav are for sonar files (.gsf, .all, .xtf)");
    }
    inspect_bundle(inputs.front(), o.json);
  } else {
    inspect_sonar_files(o);
  }
}

}  // namespace

void add_inspect_command(CLI::App& app) {
  auto options = std::make_shared<InspectOptions>();
  CLI::App* cmd = app.add_subcommand("inspect", "Validate a survey (bundle, GSF, Kongsberg .all or XTF files) and summarise it");
  add_survey_options(cmd, options->survey);
  cmd->add_flag("--json", options->json, "print the summary as JSON");
  cmd->callback([options] { run_inspect(*options); });
}

}  // namespace bathyslam::cli
