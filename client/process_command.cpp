#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "client/commands.h"
#include "client/survey_options.h"
#include "core/fuse/difference.h"
#include "core/fuse/fuse.h"
#include "core/fuse/soundings_csv.h"
#include "core/io/bundle.h"
#include "core/io/file_bytes.h"
#include "core/io/gsf/gsf_survey.h"
#include "core/io/gsf/navigation_rewrite.h"
#include "core/pipeline/corrected_navigation.h"
#include "core/pipeline/job_input.h"
#include "core/pipeline/parameters.h"
#include "core/pipeline/pipeline.h"
#include "core/pipeline/report.h"
#include "core/products/corrected_gsf.h"
#include "core/products/difference_products.h"
#include "core/products/map_products.h"

namespace bathyslam::cli {
namespace {

struct ProcessOptions {
  SurveyOptions survey;
  std::string config = "mchs";
  std::vector<std::string> sets;
  int threads = 0;
  FuseConfig fuse;
  bool export_gsf = false;
  bool export_soundings = false;
  DifferenceConfig difference;
  std::string reference;  // several surveys: the one held (the datum), moved to the front
  std::string out;
};

// A bundle, .all or .xtf files read again: their pings with the corrected navigation as one GSF
// file (the one the service stores for a job); `survey_index`: the survey's place in a site.
void export_pings_as_gsf(const SurveyInput& input, const Survey& survey, const PipelineResult& result,
                         const std::filesystem::path& path, int survey_index = 0) {
  const std::uint64_t pings = write_corrected_gsf(
      survey, result, path,
      [&](PingSink& sink) {
        BundleReadResult read;
        read.survey = load_survey(input, sink).survey;
        return read;
      },
      survey_index);
  std::printf("%s: %llu pings with the corrected navigation\n", path.filename().c_str(),
              static_cast<unsigned long long>(pings));
}

// GSF input: each file copied with the corrected navigation in its ping headers
// (OUT/<name>.corrected.gsf); a bundle, .all or .xtf files: their pings written as OUT/corrected.gsf.
void export_gsf(const ProcessOptions& o, const Survey& survey, const PipelineResult& result,
                const std::vector<NavSample>& corrected) {
  const std::filesystem::path out(o.out);
  if (!gsf::is_gsf_path(o.survey.inputs.front())) {
    export_pings_as_gsf(o.survey.input(), survey, result, out / kCorrectedGsfFile);
    return;
  }
  for (const std::filesystem::path input : o.survey.inputs) {
    const std::string name = input.stem().string() + ".corrected.gsf";
    const gsf::RewriteCount n = gsf::rewrite_navigation(input, out / name, corrected, survey.metadata.crs);
    std::printf("%s: %llu of %llu pings with the corrected navigation, all %llu records kept\n", name.c_str(),
                static_cast<unsigned long long>(n.rewritten), static_cast<unsigned long long>(n.pings),
                static_cast<unsigned long long>(n.records));
  }
}

// Several bundles: each survey's own corrected GSF, corrected.gsf for the first and
// corrected.<k>.gsf for the k-th, as its trajectory.
void export_site_gsf(const ProcessOptions& o, const std::vector<Survey>& site, const PipelineResult& result) {
  for (std::size_t k = 0; k < site.size(); ++k) {
    SurveyOptions one = o.survey;
    one.inputs = {o.survey.inputs[k]};
    export_pings_as_gsf(one.input(), site[k], result, std::filesystem::path(o.out) / corrected_gsf_name(static_cast<int>(k) + 1),
                        static_cast<int>(k));
  }
}

// Several bundles: several surveys of one site, each read alone, joined in one graph.
JobInput read_site(const ProcessOptions& o, const PipelineConfig& config, std::vector<Survey>& surveys) {
  std::vector<SurveyReader> reads;
  for (const std::string& path : o.survey.inputs) {
    SurveyOptions one = o.survey;
    one.inputs = {path};
    reads.push_back([one](PingSink& sink) { return load_survey(one.input(), sink).survey; });
  }
  return read_site_input(reads, o.survey.inputs, config, o.fuse, surveys);
}

// The change between two surveys of the site: difference_<j>_<k>.{tif,json}.
void print_difference(const DifferenceProducts& d, double k_sigma) {
  if (d.map.cells_compared == 0) {
    std::printf("%s: the surveys share no cell of the map\n", d.stem.c_str());
    return;
  }
  std::printf("%s.tif, .json: %zu of %zu cells changed beyond %g sigma (registration: local offsets rms %.3f m taken out, "
              "sigma %.3f m vertical, %.3f m horizontal), %zu areas\n",
              d.stem.c_str(), d.map.cells_significant, d.map.cells_compared, k_sigma, d.map.offset_rms_m, d.map.sigma_vertical_m,
              d.map.sigma_horizontal_m, d.map.areas.size());
  for (std::size_t i = 0; i < std::min<std::size_t>(d.map.areas.size(), 5); ++i) {
    const ChangedArea& area = d.map.areas[i];
    std::printf("  %8.0f m2 at (%.1f, %.1f): +%.1f m3, -%.1f m3, largest %+.2f m\n", area.area_m2,
                area.easting, area.northing, area.gained_m3, area.lost_m3,
                area.largest_change_m);
  }
}

// Several bundles (folders or .tar files) are several surveys; several sonar files are one.
bool is_site(const ProcessOptions& o) {
  const std::filesystem::path first = o.survey.inputs.front();
  return o.survey.inputs.size() > 1 && (std::filesystem::is_directory(first) || first.extension() == ".tar");
}

// The surveys with --reference first: the job's datum, and the "1" of every difference.
ProcessOptions with_reference_first(ProcessOptions o) {
  if (o.reference.empty()) return o;
  auto same = [&](const std::string& input) {
    std::error_code error;
    return input == o.reference || std::filesystem::equivalent(input, o.reference, error);
  };
  auto reference = std::find_if(o.survey.inputs.begin(), o.survey.inputs.end(), same);
  if (reference == o.survey.inputs.end() || !is_site(o))
    throw std::invalid_argument("--reference: " + o.reference + " is not one of the surveys (bundles) given");
  std::rotate(o.survey.inputs.begin(), reference, reference + 1);
  return o;
}

void run_process(const ProcessOptions& o) {
  PipelineConfig config = configuration_of(o.config, overrides_of(o.sets));
  config.threads = o.threads;

  const auto start = std::chrono::steady_clock::now();
  // Nothing reads the soundings again but --export-gsf, which reads the input again.
  std::vector<Survey> site;
  JobInput input = is_site(o) ? read_site(o, config, site)
                              : read_job_input([&](PingSink& sink) { return load_survey(o.survey.input(), sink).survey; },
                                               config, o.fuse);
  const Survey& survey = input.survey;
  const FuseConfig& fuse = input.fuse;
  std::string last_stage;
  const ProgressFn progress = [&](std::string_view stage, double fraction) {
    if (stage != last_stage) {
      if (!last_stage.empty()) std::fprintf(stderr, "\n");
      last_stage = stage;
    }
    std::fprintf(stderr, "\r  %-10s %5.1f %%", std::string(stage).c_str(), 100.0 * fraction);
  };
  PipelineResult result = run_pipeline(std::move(input.submaps), input.read_seconds, config, progress);
  discount_change_across_surveys(result, fuse, o.difference);
  std::fprintf(stderr, "\n");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::filesystem::create_directories(o.out);
  const std::vector<NavSample> corrected = corrected_navigation(survey, result);
  write_nav_csv(corrected, std::filesystem::path(o.out) / "trajectory.csv");
  for (std::size_t k = 1; k < site.size(); ++k) {  // the first survey's is trajectory.csv
    write_nav_csv(corrected_navigation(site[k], result, static_cast<int>(k)),
                  std::filesystem::path(o.out) / ("trajectory." + std::to_string(k + 1) + ".csv"));
  }
  const nlohmann::json report = report_json(result);
  {
    const std::filesystem::path path = std::filesystem::path(o.out) / "report.json";
    std::ofstream out(path);
    out << report.dump(2) << '\n';
    close_checked(out, path);
  }
  write_report_plots(result, o.out);
  const auto fuse_start = std::chrono::steady_clock::now();
  const std::string map_files = write_map_products(result, survey.metadata, fuse, o.out).summary();
  const double fuse_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - fuse_start).count();
  std::printf("%s", report_text(result).c_str());
  if (o.export_gsf && site.empty()) export_gsf(o, survey, result, corrected);
  if (o.export_gsf && !site.empty()) export_site_gsf(o, site, result);
  if (o.export_soundings) {
    const std::uint64_t n =
        write_soundings_csv(result.submaps, result.optimized_poses, std::filesystem::path(o.out) / "soundings.csv");
    std::printf("soundings.csv: %llu corrected soundings\n", static_cast<unsigned long long>(n));
  }
  std::printf("map %.2f m cells: %s (%.1f s)\n", fuse.resolution_m, map_files.c_str(), fuse_seconds);
  for (const auto& [before, after] : difference_pairs(static_cast<int>(site.size()))) {
    print_difference(write_difference_products(result, survey.metadata, fuse, before, after, o.difference, o.out),
                     o.difference.k_sigma);
  }
  std::printf("total %.1f s; wrote %s/{trajectory.csv, report.json, *.png, map.tif, map.bag, tiles/}\n", seconds + fuse_seconds,
              o.out.c_str());
}

}  // namespace

void add_process_command(CLI::App& app) {
  auto options = std::make_shared<ProcessOptions>();
  CLI::App* cmd = app.add_subcommand("process", "Run a SLAM configuration on a survey offline");
  add_survey_options(cmd, options->survey);
  cmd->add_option("--config", options->config, "odometry, gicp or mchs")
      ->check(CLI::IsMember(std::vector<std::string>(kConfigurationNames.begin(), kConfigurationNames.end())))
      ->capture_default_str();
  cmd->add_option("--set", options->sets, "override a parameter: key=value (repeatable)");
  cmd->add_option("--threads", options->threads, "registration threads (0: all cores)")->capture_default_str();
  options->fuse.resolution_m = 0;
  cmd->add_option("--resolution", options->fuse.resolution_m,
                  "map cell size in metres (0: from the sounding density, 0.5 m or coarser)")
      ->check(CLI::Range(0.0, 10000.0))
      ->capture_default_str();
  cmd->add_option("--min-soundings", options->fuse.min_soundings, "fewer soundings in a cell: no data")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_flag("--export-gsf", options->export_gsf,
                "also write the pings with the corrected navigation: GSF input file by file "
                "(NAME.corrected.gsf, every record kept), a bundle as corrected.gsf; several surveys each their own "
                "(corrected.gsf for the first, corrected.K.gsf for the K-th)");
  cmd->add_flag("--export-soundings", options->export_soundings,
                "also write soundings.csv: every corrected sounding (easting,northing,elevation,line,submap)");
  cmd->add_option("--change-sigmas", options->difference.k_sigma,
                  "several surveys: a cell changed between two of them beyond this many standard deviations is significant")
      ->check(CLI::Range(0.1, 100.0))
      ->capture_default_str();
  cmd->add_option("--reference", options->reference,
                  "several surveys: the one held in place (the datum; the first by default); differences are from it");
  cmd->add_option("--out", options->out, "output folder")->required();
  cmd->callback([options] { run_process(with_reference_first(*options)); });
}

}  // namespace bathyslam::cli
