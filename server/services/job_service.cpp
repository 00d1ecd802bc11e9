#include "server/services/job_service.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <map>
#include <thread>

#include "core/pipeline/parameters.h"
#include "core/pipeline/pipeline.h"
#include "core/pipeline/report.h"
#include "server/log.h"

namespace bathyslam::server {
namespace {

namespace storage = bathyslam::storage;

// WatchJob sleeps until the job's bell rings, and checks this often that its call is still there;
// while the bell cannot listen (the database restarting), it reads the job this often instead.
constexpr auto kWatchFallback = std::chrono::seconds(2);

v1::JobState to_proto(storage::JobState state) {
  switch (state) {
    case storage::JobState::kQueued: return v1::QUEUED;
    case storage::JobState::kRunning: return v1::RUNNING;
    case storage::JobState::kSucceeded: return v1::SUCCEEDED;
    case storage::JobState::kFailed: return v1::FAILED;
    case storage::JobState::kCancelled: return v1::CANCELLED;
  }
  return v1::JOB_STATE_UNSPECIFIED;
}

void describe(const storage::JobRecord& job, v1::Job* reply) {
  reply->set_id(job.id);
  reply->set_survey_id(job.survey_id);
  for (std::int64_t id : job.more_survey_ids) reply->add_more_survey_ids(id);
  reply->set_site_id(job.site_id.value_or(0));
  reply->set_configuration(job.configuration);
  reply->set_state(to_proto(job.state));
  reply->set_stage(job.stage);
  reply->set_progress(job.progress);
  reply->set_attempts(job.attempts);
  reply->set_error(job.error.value_or(""));
  reply->set_created_at(job.created_at);
  reply->set_started_at(job.started_at);
  reply->set_finished_at(job.finished_at);
  for (const auto& [name, value] : job.parameters.items())
    if (value.is_number()) (*reply->mutable_parameters())[name] = value.get<double>();
}

void stats(const ErrorStats& s, v1::ErrorStats* out) {
  out->set_rmse(s.rmse);
  out->set_mean(s.mean);
  out->set_std(s.std);
  out->set_p50(s.p50);
  out->set_p95(s.p95);
  out->set_p99(s.p99);
  out->set_max(s.max);
  out->set_count(static_cast<std::int64_t>(s.count));
}

void constraint_stats(const std::map<std::string, ConstraintCounts>& groups,
                      google::protobuf::RepeatedPtrField<v1::ConstraintStats>* out) {
  for (const auto& [name, c] : groups) {
    v1::ConstraintStats* stats = out->Add();
    stats->set_name(name);
    stats->set_candidates(c.candidates);
    stats->set_accepted(c.accepted);
    stats->set_rejected(c.rejected);
    for (const auto& [kind, n] : c.rejections) (*stats->mutable_rejection_reasons())[kind] = n;
  }
}

// Core's messages quote a configuration, a parameter's name and its value whole; their text is
// bounded here first (the longest parameter name has about 50 bytes, a number fewer).
constexpr std::size_t kMaxParameterBytes = 128;

// The effective configuration: the configuration's preset, then the overrides, each checked by name and range.
PipelineConfig effective_config(const v1::SubmitJobRequest& request) {
  check_name("configuration", request.configuration(), kMaxParameterBytes);
  for (const auto& [name, value] : request.parameters()) {
    check_name("parameters", name, kMaxParameterBytes);
    check_name("parameters[" + name + "]", value, kMaxParameterBytes);
  }
  try {
    return configuration_of(request.configuration(),
                            std::map<std::string, std::string>(request.parameters().begin(), request.parameters().end()));
  } catch (const ConfigurationError& error) {
    throw invalid(error.field(), error.what());
  }
}

}  // namespace

std::vector<JobService::NamedSurvey> JobService::requested_surveys(std::int64_t tenant,
                                                                   const v1::SubmitJobRequest& request) {
  std::vector<NamedSurvey> surveys;
  if (request.site_id() != 0) {
    if (request.survey_id() != 0 || request.more_survey_ids_size() > 0)
      throw invalid("site_id", "a job names a site or its surveys (survey_id, more_survey_ids), not both");
    const storage::SiteRecord site = owned_site(context_, tenant, request.site_id());
    if (site.survey_ids.empty())
      throw Refusal(grpc::StatusCode::FAILED_PRECONDITION,
                    "site_id: site " + std::to_string(site.id) + " has no surveys; add some first (AddSurveys)");
    for (std::int64_t id : site.survey_ids) surveys.push_back({id, "site_id"});
  } else {
    if (request.more_survey_ids_size() > kMaxSiteSurveys - 1)
      throw invalid("more_survey_ids", std::to_string(request.more_survey_ids_size()) + " surveys; a job joins at most " +
                                           std::to_string(kMaxSiteSurveys) + " with survey_id");
    surveys.push_back({request.survey_id(), "survey_id"});
    for (int k = 0; k < request.more_survey_ids_size(); ++k)
      surveys.push_back({request.more_survey_ids(k), "more_survey_ids[" + std::to_string(k) + "]"});
  }
  if (request.reference_survey_id() != 0) {
    auto reference = std::find_if(surveys.begin(), surveys.end(),
                                  [&](const NamedSurvey& s) { return s.id == request.reference_survey_id(); });
    if (reference == surveys.end())
      throw invalid("reference_survey_id", "survey " + std::to_string(request.reference_survey_id()) +
                                               " is not one of the job's surveys");
    std::rotate(surveys.begin(), reference, reference + 1);
  }
  return surveys;
}

storage::SurveyRecord JobService::check_surveys(std::int64_t tenant, const std::vector<NamedSurvey>& surveys) {
  std::vector<storage::SurveyRecord> records;
  for (const NamedSurvey& named : surveys) {
    const storage::SurveyRecord survey = owned_survey(context_, tenant, named.id, named.field);
    const bool twice = std::any_of(records.begin(), records.end(), [&](const auto& r) { return r.id == survey.id; });
    if (twice) throw invalid(named.field, "survey " + std::to_string(survey.id) + " is already in the job");
    if (!survey.ready)
      throw Refusal(grpc::StatusCode::FAILED_PRECONDITION,
                    named.field + ": survey " + std::to_string(survey.id) + " is not ready; finalize it without errors first");
    if (!records.empty() && survey.crs != records.front().crs)
      throw invalid(named.field, "survey " + std::to_string(survey.id) + " is in " + survey.crs + ", survey " +
                                     std::to_string(records.front().id) + " in " + records.front().crs +
                                     ": surveys of one site share a CRS");
    records.push_back(survey);
  }
  return records.front();
}

grpc::Status JobService::SubmitJob(grpc::ServerContext* call, const v1::SubmitJobRequest* request, v1::Job* reply) {
  return handle("SubmitJob", call, [&] {
    const std::int64_t tenant = caller_tenant(context_, *call);
    const std::vector<NamedSurvey> surveys = requested_surveys(tenant, *request);
    owned_survey(context_, tenant, surveys.front().id, surveys.front().field);  // NOT_FOUND before anything else
    const PipelineConfig config = effective_config(*request);
    const storage::SurveyRecord survey = check_surveys(tenant, surveys);
    storage::NewJob job{survey.id, to_string(config.configuration), parameters(config), context_.limits.max_attempts};
    for (std::size_t k = 1; k < surveys.size(); ++k) job.more_survey_ids.push_back(surveys[k].id);
    if (request->site_id() != 0) job.site_id = request->site_id();
    const std::optional<std::int64_t> queued =
        context_.jobs.enqueue_within_limit(job, tenant, context_.limits.max_active_jobs);
    if (!queued)
      throw Refusal(grpc::StatusCode::RESOURCE_EXHAUSTED,
                    std::to_string(context_.limits.max_active_jobs) + " jobs are queued or running; the limit is " +
                        std::to_string(context_.limits.max_active_jobs));
    const std::int64_t id = *queued;
    log("job %lld queued: survey %lld, %s, %d overrides", static_cast<long long>(id), static_cast<long long>(survey.id),
        job.configuration.c_str(), request->parameters_size());
    describe(*context_.jobs.job(id), reply);
  });
}

grpc::Status JobService::GetJob(grpc::ServerContext* call, const v1::GetJobRequest* request, v1::Job* reply) {
  return handle("GetJob", call, [&] { describe(owned_job(context_, caller_tenant(context_, *call), request->job_id()), reply); });
}

grpc::Status JobService::WatchJob(grpc::ServerContext* call, const v1::WatchJobRequest* request,
                                  grpc::ServerWriter<v1::JobEvent>* writer) {
  return handle("WatchJob", call, [&] {
    const std::int64_t tenant = caller_tenant(context_, *call);
    storage::JobRecord job = owned_job(context_, tenant, request->job_id());
    // Held while the stream is open: each holds a server thread, and one tenant's thousands
    // slowed every other tenant's calls to seconds.
    const StreamSlots::Slot slot =
        slot_or_refuse(watch_slots_, tenant, "WatchJob streams open", "--max-watch-streams", "close one first");
    std::int64_t last_event = 0;
    // Until the client goes away (or its deadline passes) or the job ends.
    while (!call->IsCancelled()) {
      // The bell's count before reading: a change from here on wakes the wait below.
      const std::uint64_t rings = bell_.rings(job.id);
      // The state first: events written before a final state are all read below.
      auto now = context_.jobs.job(job.id);
      if (!now) throw Refusal(grpc::StatusCode::NOT_FOUND, "job_id: job " + std::to_string(job.id) + " was deleted");
      job = *now;
      for (const storage::StoredJobEvent& stored : context_.jobs.events_after(job.id, last_event)) {
        v1::JobEvent event;
        event.set_job_id(job.id);
        event.set_stage(stored.event.stage);
        event.set_progress(stored.event.progress);
        event.set_message(stored.event.message);
        event.set_at(stored.at);
        event.set_attempt(stored.event.attempt);
        event.set_state(finished(job.state) ? v1::RUNNING : to_proto(job.state));
        if (!writer->Write(event)) return;
        last_event = stored.id;
      }
      if (finished(job.state)) {
        v1::JobEvent end;
        end.set_job_id(job.id);
        end.set_stage(storage::to_string(job.state));
        end.set_progress(job.state == storage::JobState::kSucceeded ? 1 : job.progress);
        end.set_message(job.error.value_or(""));
        end.set_at(job.finished_at);
        end.set_state(to_proto(job.state));
        end.set_attempt(job.attempts);
        writer->Write(end);
        return;
      }
      // While the bell listens, a watcher reads the database only when its job rang, so that
      // idle watchers cost it nothing however many there are; between rings it only checks
      // that its call is still there.
      while (!bell_.wait(job.id, rings, kWatchFallback))
        if (call->IsCancelled()) return;
    }
  });
}

grpc::Status JobService::CancelJob(grpc::ServerContext* call, const v1::CancelJobRequest* request, v1::Job* reply) {
  return handle("CancelJob", call, [&] {
    const storage::JobRecord job = owned_job(context_, caller_tenant(context_, *call), request->job_id());
    if (!context_.jobs.cancel(job.id))
      throw Refusal(grpc::StatusCode::FAILED_PRECONDITION,
                    "job_id: job " + std::to_string(job.id) + " has " + storage::to_string(context_.jobs.job(job.id)->state) +
                        " already");
    log("job %lld cancelled by the client", static_cast<long long>(job.id));
    describe(*context_.jobs.job(job.id), reply);
  });
}

grpc::Status JobService::ListJobs(grpc::ServerContext* call, const v1::ListJobsRequest* request, v1::ListJobsResponse* reply) {
  return handle("ListJobs", call, [&] {
    const std::int64_t tenant = caller_tenant(context_, *call);
    std::optional<std::int64_t> survey;
    if (request->survey_id() != 0) survey = owned_survey(context_, tenant, request->survey_id()).id;
    std::optional<std::int64_t> site;
    if (request->site_id() != 0) site = owned_site(context_, tenant, request->site_id()).id;
    const int size = page_size(request->page_size());
    auto jobs = context_.jobs.list_jobs(tenant, survey, page_token(request->page_token()), size + 1, site);
    const bool more = trim_to_page(jobs, size);
    for (const storage::JobRecord& job : jobs) describe(job, reply->add_jobs());
    if (more) reply->set_next_page_token(std::to_string(jobs.back().id));
  });
}

grpc::Status JobService::GetReport(grpc::ServerContext* call, const v1::GetReportRequest* request, v1::Report* reply) {
  return handle("GetReport", call, [&] {
    const storage::JobRecord job = job_with_results(context_, caller_tenant(context_, *call), request->job_id());
    auto report = context_.results.load_report(job.id);
    if (!report)
      throw Refusal(grpc::StatusCode::FAILED_PRECONDITION,
                    "job_id: job " + std::to_string(job.id) + " is " + storage::to_string(job.state) + " and has no report");
    const nlohmann::json& r = report->report;
    reply->set_job_id(job.id);
    const ReportSummary summary = report_summary_from_json(r);
    reply->set_configuration(summary.configuration);
    stats(summary.consistency, reply->mutable_consistency());
    stats(summary.consistency_dr, reply->mutable_consistency_dr());
    stats(summary.trajectory, reply->mutable_trajectory());
    stats(summary.trajectory_dr, reply->mutable_trajectory_dr());
    reply->set_histogram_bin_width_m(summary.histogram.bin_width);
    for (const std::size_t count : summary.histogram.counts) reply->add_histogram_counts(static_cast<std::int64_t>(count));
    constraint_stats(summary.by_type, reply->mutable_constraints_by_type());
    constraint_stats(summary.by_path, reply->mutable_constraints_by_path());
    for (const auto& [name, png] : report->plots) {
      v1::Plot* plot = reply->add_plots();
      plot->set_name(name);
      plot->set_png(png.data(), png.size());
    }
    reply->set_report_json(r.dump());
  });
}

}  // namespace bathyslam::server
