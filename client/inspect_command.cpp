#include <cstdio>
#include <memory>
#include <string>

#include "client/commands.h"
#include "core/io/bundle.h"
#include "core/summary/survey_summary.h"

namespace bathyslam::cli {
namespace {

struct InspectOptions {
  std::string bundle;
  bool json = false;
};

void run_inspect(const InspectOptions& o) {
  BundleReadResult result = read_bundle(o.bundle);
  for (const Problem& p : result.problems) {
    if (p.file.empty()) std::fprintf(stderr, "%s\n", p.to_string().c_str());
    else std::fprintf(stderr, "%s/%s\n", o.bundle.c_str(), p.to_string().c_str());
  }
  if (!result.survey) throw std::runtime_error(o.bundle + ": not a valid survey bundle");
  const SurveySummary summary = summarize(*result.survey);
  if (o.json) {
    std::printf("%s\n", to_json(summary).dump(2).c_str());
  } else {
    std::printf("%s", to_text(summary).c_str());
  }
}

}  // namespace

void add_inspect_command(CLI::App& app) {
  auto options = std::make_shared<InspectOptions>();
  CLI::App* cmd = app.add_subcommand("inspect", "Validate a survey bundle and summarise it");
  cmd->add_option("bundle", options->bundle, "survey bundle: a folder or a .tar of one")->required();
  cmd->add_flag("--json", options->json, "print the summary as JSON");
  cmd->callback([options] { run_inspect(*options); });
}

}  // namespace bathyslam::cli
