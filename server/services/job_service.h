#pragma once
// bathyslam.v1.JobService: submit SLAM jobs, follow them, cancel them, read their reports.
#include <cstdint>
#include <string>
#include <vector>

#include "bathyslam/v1/job.grpc.pb.h"
#include "server/services/job_event_bell.h"
#include "server/services/service_context.h"
#include "server/services/stream_slots.h"

namespace bathyslam::server {

class JobService final : public v1::JobService::Service {
 public:
  JobService(ServiceContext& context, JobEventBell& bell)
      : context_(context), bell_(bell), watch_slots_(context.limits.max_watch_streams) {}

  grpc::Status SubmitJob(grpc::ServerContext* call, const v1::SubmitJobRequest* request, v1::Job* reply) override;
  grpc::Status GetJob(grpc::ServerContext* call, const v1::GetJobRequest* request, v1::Job* reply) override;
  grpc::Status WatchJob(grpc::ServerContext* call, const v1::WatchJobRequest* request,
                        grpc::ServerWriter<v1::JobEvent>* writer) override;
  grpc::Status CancelJob(grpc::ServerContext* call, const v1::CancelJobRequest* request, v1::Job* reply) override;
  grpc::Status ListJobs(grpc::ServerContext* call, const v1::ListJobsRequest* request, v1::ListJobsResponse* reply) override;
  grpc::Status GetReport(grpc::ServerContext* call, const v1::GetReportRequest* request, v1::Report* reply) override;

 private:
  // One of a job's surveys as the request named it: the field a refusal names.
  struct NamedSurvey {
    std::int64_t id = 0;
    std::string field;
  };
  // The job's surveys in order, the datum first: the site's (site_id) or survey_id and
  // more_survey_ids, with reference_survey_id moved to the front.
  std::vector<NamedSurvey> requested_surveys(std::int64_t tenant, const v1::SubmitJobRequest& request);
  // Each of `surveys` the caller's, ready, not twice, in one CRS; the first's record.
  storage::SurveyRecord check_surveys(std::int64_t tenant, const std::vector<NamedSurvey>& surveys);
  ServiceContext& context_;
  JobEventBell& bell_;
  StreamSlots watch_slots_;
};

}  // namespace bathyslam::server
