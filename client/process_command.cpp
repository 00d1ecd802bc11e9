#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "client/commands.h"
#include "core/io/bundle.h"
#include "core/pipeline/pipeline.h"
#include "core/pipeline/report.h"

namespace bathyslam::cli {
namespace {

struct ProcessOptions {
  std::string bundle;
  std::string config = "gicp";
  std::vector<std::string> sets;
  int threads = 0;
  std::string out;
};

void run_process(const ProcessOptions& o) {
  PipelineConfig config;
  config.configuration = parse_configuration(o.config);
  config.threads = o.threads;
  for (const std::string& kv : o.sets) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos) throw std::invalid_argument("--set expects key=value, got '" + kv + "'");
    set_parameter(config, kv.substr(0, eq), kv.substr(eq + 1));
  }

  const auto start = std::chrono::steady_clock::now();
  const Survey survey = load_bundle(o.bundle);
  std::string last_stage;
  const PipelineResult result = run_pipeline(survey, config, [&](std::string_view stage, double fraction) {
    if (stage != last_stage) {
      if (!last_stage.empty()) std::fprintf(stderr, "\n");
      last_stage = stage;
    }
    std::fprintf(stderr, "\r  %-10s %5.1f %%", std::string(stage).c_str(), 100.0 * fraction);
  });
  std::fprintf(stderr, "\n");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::filesystem::create_directories(o.out);
  write_nav_csv(corrected_navigation(survey, result), std::filesystem::path(o.out) / "trajectory.csv");
  const nlohmann::json report = report_json(result);
  {
    std::ofstream out(std::filesystem::path(o.out) / "report.json");
    out << report.dump(2) << '\n';
    if (!out) throw std::runtime_error(o.out + "/report.json: cannot write");
  }
  write_report_plots(result, o.out);
  std::printf("%s", report_summary(result).c_str());
  std::printf("total %.1f s; wrote %s/{trajectory.csv, report.json, *.png}\n", seconds, o.out.c_str());
}

}  // namespace

void add_process_command(CLI::App& app) {
  auto options = std::make_shared<ProcessOptions>();
  CLI::App* cmd = app.add_subcommand("process", "Run a SLAM configuration on a survey bundle offline");
  cmd->add_option("bundle", options->bundle, "survey bundle folder")->required();
  cmd->add_option("--config", options->config, "odometry or gicp")
      ->check(CLI::IsMember({"odometry", "gicp"}))
      ->capture_default_str();
  cmd->add_option("--set", options->sets, "override a parameter: key=value (repeatable)");
  cmd->add_option("--threads", options->threads, "registration threads (0: all cores)")->capture_default_str();
  cmd->add_option("--out", options->out, "output folder")->required();
  cmd->callback([options] { run_process(*options); });
}

}  // namespace bathyslam::cli
