// bathyslam submit / watch / jobs / report: SLAM jobs on the server.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bathyslam/v1/job.grpc.pb.h"
#include "client/commands.h"
#include "client/remote.h"
#include "core/io/file_bytes.h"
#include "core/pipeline/parameters.h"
#include "core/types/format.h"

namespace bathyslam::cli {
namespace {

std::span<const std::uint8_t> bytes_of(const std::string& text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

std::string state_name(v1::JobState state) {
  std::string name = v1::JobState_Name(state);
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name;
}

struct SubmitOptions {
  Remote remote;
  std::int64_t survey = 0;
  std::vector<std::int64_t> surveys;  // --surveys: several of one site, the first the datum
  std::int64_t site = 0;              // --site: every survey of a site
  std::int64_t reference = 0;         // --reference: the datum, when not the first
  std::string config = "mchs";
  std::vector<std::string> sets;
};

void run_submit(const SubmitOptions& o) {
  v1::SubmitJobRequest request;
  if ((o.survey != 0) + !o.surveys.empty() + (o.site != 0) != 1)
    throw std::invalid_argument("submit: give one survey id, --surveys A,B,... or --site ID");
  if (o.site != 0) request.set_site_id(o.site);
  else request.set_survey_id(o.survey != 0 ? o.survey : o.surveys.front());
  for (std::size_t k = 1; k < o.surveys.size(); ++k) request.add_more_survey_ids(o.surveys[k]);
  request.set_reference_survey_id(o.reference);
  request.set_configuration(o.config);
  // Parsed as `process` parses them; the server checks names and values (configuration_of).
  for (const auto& [name, value] : overrides_of(o.sets)) (*request.mutable_parameters())[name] = value;
  v1::Job job;
  check("SubmitJob", v1::JobService::NewStub(o.remote.channel())->SubmitJob(o.remote.context(30).get(), request, &job));
  std::printf("job %lld %s\n", static_cast<long long>(job.id()), state_name(job.state()).c_str());
}

struct JobOptions {
  Remote remote;
  std::int64_t job = 0;
  std::int64_t survey = 0;
  std::int64_t site = 0;
  bool json = false;
  std::string out;
};

// One progress bar per stage: the bar of a stage is finished when the next stage starts.
void run_watch(const JobOptions& o) {
  auto context = o.remote.context();
  v1::WatchJobRequest request;
  request.set_job_id(o.job);
  auto reader = v1::JobService::NewStub(o.remote.channel())->WatchJob(context.get(), request);
  v1::JobEvent event;
  std::string stage;
  v1::JobState state = v1::JOB_STATE_UNSPECIFIED;
  std::string message;
  while (reader->Read(&event)) {
    state = event.state();
    message = event.message();
    const bool end = state == v1::SUCCEEDED || state == v1::FAILED || state == v1::CANCELLED;
    if (end) break;
    if (event.stage() != stage && !stage.empty()) std::fprintf(stderr, "\n");
    stage = event.stage();
    progress_line(stage, event.progress(), event.message());
  }
  if (!stage.empty()) std::fprintf(stderr, "\n");
  check("WatchJob", reader->Finish());
  std::printf("job %lld %s%s%s\n", static_cast<long long>(o.job), state_name(state).c_str(),
              message.empty() ? "" : ": ", message.c_str());
  if (state != v1::SUCCEEDED) throw std::runtime_error("job " + std::to_string(o.job) + " did not succeed");
}

std::string when(double seconds) { return seconds <= 0 ? "-" : format_utc(seconds, "%Y-%m-%d %H:%M:%S"); }

void run_jobs(const JobOptions& o) {
  auto stub = v1::JobService::NewStub(o.remote.channel());
  v1::ListJobsRequest request;
  request.set_survey_id(o.survey);
  request.set_site_id(o.site);
  std::printf("%6s %6s  %-9s %-10s %-10s %6s  %-19s %8s  %s\n", "job", "survey", "config", "state", "stage", "%",
              "created (UTC)", "run (s)", "error");
  do {
    v1::ListJobsResponse page;
    check("ListJobs", stub->ListJobs(o.remote.context(30).get(), request, &page));
    for (const v1::Job& job : page.jobs()) {
      const double end = job.finished_at() > 0 ? job.finished_at() : static_cast<double>(std::time(nullptr));
      std::printf("%6lld %6lld  %-9s %-10s %-10s %6.1f  %-19s %8s  %s\n", static_cast<long long>(job.id()),
                  static_cast<long long>(job.survey_id()), job.configuration().c_str(), state_name(job.state()).c_str(),
                  job.stage().c_str(), 100 * job.progress(), when(job.created_at()).c_str(),
                  job.started_at() > 0 ? std::to_string(static_cast<int>(end - job.started_at())).c_str() : "-",
                  job.error().c_str());
    }
    request.set_page_token(page.next_page_token());
  } while (!request.page_token().empty());
}

// `figure`: the report.json section whose "not_computed" says why a figure with no values has none.
void print_stats(const char* label, const v1::ErrorStats& s, const v1::ErrorStats& dr, const nlohmann::json& figure) {
  if (figure.contains("not_computed")) {
    std::printf("%-22s not computed: %s\n", label, figure["not_computed"].get<std::string>().c_str());
    return;
  }
  std::printf("%-22s %9.3f %9.3f %9.3f %9.3f %9.3f %9lld   (dead reckoning: rmse %.3f, p95 %.3f)\n", label, s.rmse(),
              s.mean(), s.p95(), s.p99(), s.max(), static_cast<long long>(s.count()), dr.rmse(), dr.p95());
}

void print_constraints(const char* heading, const google::protobuf::RepeatedPtrField<v1::ConstraintStats>& groups) {
  std::printf("\n%-14s %10s %9s %9s  %s\n", heading, "candidates", "accepted", "rejected", "rejection reasons");
  for (const v1::ConstraintStats& c : groups) {
    std::string reasons;
    for (const auto& [reason, n] : c.rejection_reasons()) reasons += (reasons.empty() ? "" : "; ") + std::to_string(n) + " × " + reason;
    std::printf("%-14s %10lld %9lld %9lld  %s\n", c.name().c_str(), static_cast<long long>(c.candidates()),
                static_cast<long long>(c.accepted()), static_cast<long long>(c.rejected()), reasons.c_str());
  }
}

void run_report(const JobOptions& o) {
  v1::GetReportRequest request;
  request.set_job_id(o.job);
  v1::Report report;
  check("GetReport", v1::JobService::NewStub(o.remote.channel())->GetReport(o.remote.context(60).get(), request, &report));
  if (!o.out.empty()) {
    std::filesystem::create_directories(o.out);
    const std::string json = nlohmann::json::parse(report.report_json()).dump(2) + '\n';
    write_file_bytes(std::filesystem::path(o.out) / "report.json", bytes_of(json));
    for (const v1::Plot& plot : report.plots())
      write_file_bytes(std::filesystem::path(o.out) / std::filesystem::path(plot.name()).filename(), bytes_of(plot.png()));
  }
  if (o.json) {
    std::printf("%s\n", nlohmann::json::parse(report.report_json()).dump(2).c_str());
  } else {
    const nlohmann::json full = nlohmann::json::parse(report.report_json());
    std::printf("job %lld, configuration %s\n\n", static_cast<long long>(report.job_id()), report.configuration().c_str());
    std::printf("%-22s %9s %9s %9s %9s %9s %9s\n", "error (m)", "rmse", "mean", "p95", "p99", "max", "count");
    print_stats("consistency", report.consistency(), report.consistency_dr(), full.value("consistency_error_m", nlohmann::json::object()));
    print_stats("trajectory", report.trajectory(), report.trajectory_dr(), full.value("trajectory_error_m", nlohmann::json::object()));
    print_constraints("constraint", report.constraints_by_type());
    if (report.constraints_by_path_size() > 0) print_constraints("path", report.constraints_by_path());
    // Whether to trust the map: the safety net's verdict and what it dropped.
    const nlohmann::json net = full.value("safety_net", nlohmann::json::object());
    if (net.contains("verdict")) {
      std::printf("\nsafety net: %s\n", net["verdict"].get<std::string>().c_str());
      for (const nlohmann::json& dropped : net.value("dropped", nlohmann::json::array())) {
        std::printf("  dropped %s\n", dropped.get<std::string>().c_str());
      }
    }
  }
  if (!o.out.empty())
    std::fprintf(stderr, "saved report.json and %d plots in %s\n", report.plots_size(), o.out.c_str());
}

}  // namespace

void add_job_commands(CLI::App& app) {
  auto submit = std::make_shared<SubmitOptions>();
  CLI::App* cmd = app.add_subcommand("submit", "Submit a SLAM job on an uploaded survey; prints the job id");
  cmd->add_option("survey", submit->survey, "survey id (from upload)");
  cmd->add_option("--surveys", submit->surveys,
                  "several surveys of one site in one graph, comma-separated; the first is held (the datum) and the "
                  "report and difference maps compare the others with it")
      ->delimiter(',');
  cmd->add_option("--site", submit->site, "every survey of a site (bathyslam site), in the site's order");
  cmd->add_option("--reference", submit->reference,
                  "several surveys: the one held in place (the datum), when not the first; differences are from it");
  cmd->add_option("--config", submit->config, "odometry, gicp or mchs")->capture_default_str();
  cmd->add_option("--set", submit->sets, "override a parameter: key=value (repeatable)");
  add_remote_options(cmd, submit->remote);
  cmd->callback([submit] { run_submit(*submit); });

  auto watch = std::make_shared<JobOptions>();
  cmd = app.add_subcommand("watch", "Follow a job's progress until it ends; fails unless it succeeded");
  cmd->add_option("job", watch->job, "job id")->required();
  add_remote_options(cmd, watch->remote);
  cmd->callback([watch] { run_watch(*watch); });

  auto jobs = std::make_shared<JobOptions>();
  cmd = app.add_subcommand("jobs", "List jobs, newest first");
  cmd->add_option("--survey", jobs->survey, "only the jobs that join this survey");
  cmd->add_option("--site", jobs->site, "only the jobs submitted for this site");
  add_remote_options(cmd, jobs->remote);
  cmd->callback([jobs] { run_jobs(*jobs); });

  auto report = std::make_shared<JobOptions>();
  cmd = app.add_subcommand("report", "A job's quality report: a table, or --json; --out saves report.json and the plots");
  cmd->add_option("job", report->job, "job id")->required();
  cmd->add_flag("--json", report->json, "print the whole report as JSON");
  cmd->add_option("--out", report->out, "folder for report.json and the PNG plots");
  add_remote_options(cmd, report->remote);
  cmd->callback([report] { run_report(*report); });
}

}  // namespace bathyslam::cli
