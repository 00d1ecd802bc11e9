#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "client/commands.h"
#include "core/fuse/fuse.h"
#include "core/io/bundle.h"
#include "core/io/file_bytes.h"
#include "core/pipeline/corrected_navigation.h"
#include "core/pipeline/pipeline.h"
#include "core/pipeline/report.h"
#include "core/products/map_products.h"

namespace bathyslam::cli {
namespace {

struct ProcessOptions {
  std::string bundle;
  std::string config = "gicp";
  std::vector<std::string> sets;
  int threads = 0;
  FuseConfig fuse;
  std::string out;
};

void run_process(const ProcessOptions& o) {
  PipelineConfig config = preset_config(parse_configuration(o.config));
  config.threads = o.threads;
  for (const std::string& assignment : o.sets) set_parameter(config, assignment);

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
  const auto fuse_start = std::chrono::steady_clock::now();
  const std::string map_files = write_map_products(result, survey.metadata, o.fuse, o.out).summary();
  const double fuse_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - fuse_start).count();
  std::printf("%s", report_text(result).c_str());
  std::printf("map %.2f m cells: %s (%.1f s)\n", o.fuse.resolution_m, map_files.c_str(), fuse_seconds);
  std::printf("total %.1f s; wrote %s/{trajectory.csv, report.json, *.png, map.tif, tiles/}\n", seconds + fuse_seconds,
              o.out.c_str());
}

}  // namespace

void add_process_command(CLI::App& app) {
  auto options = std::make_shared<ProcessOptions>();
  CLI::App* cmd = app.add_subcommand("process", "Run a SLAM configuration on a survey bundle offline");
  cmd->add_option("bundle", options->bundle, "survey bundle: a folder or a .tar of one")->required();
  cmd->add_option("--config", options->config, "odometry, gicp or mchs")
      ->check(CLI::IsMember(std::vector<std::string>(kConfigurationNames.begin(), kConfigurationNames.end())))
      ->capture_default_str();
  cmd->add_option("--set", options->sets, "override a parameter: key=value (repeatable)");
  cmd->add_option("--threads", options->threads, "registration threads (0: all cores)")->capture_default_str();
  cmd->add_option("--resolution", options->fuse.resolution_m, "map cell size in metres")
      ->check(CLI::Range(0.01, 100.0))
      ->capture_default_str();
  cmd->add_option("--min-soundings", options->fuse.min_soundings, "fewer soundings in a cell: no data")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--out", options->out, "output folder")->required();
  cmd->callback([options] { run_process(*options); });
}

}  // namespace bathyslam::cli
