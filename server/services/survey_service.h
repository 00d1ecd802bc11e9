#pragma once
// bathyslam.v1.SurveyService: surveys, resumable chunked uploads and bundle validation.
#include <filesystem>

#include "bathyslam/v1/survey.grpc.pb.h"
#include "server/services/service_context.h"
#include "server/services/files_being_written.h"
#include "server/services/stream_slots.h"

namespace bathyslam::server {

class SurveyService final : public v1::SurveyService::Service {
 public:
  SurveyService(ServiceContext& context, std::filesystem::path scratch)
      : context_(context),
        scratch_(std::move(scratch)),
        upload_slots_(context.limits.max_upload_streams),
        finalize_slots_(context.limits.max_finalizes) {}

  grpc::Status CreateSurvey(grpc::ServerContext* call, const v1::CreateSurveyRequest* request, v1::Survey* reply) override;
  grpc::Status UploadFile(grpc::ServerContext* call, grpc::ServerReader<v1::UploadFileRequest>* reader,
                          v1::UploadStatus* reply) override;
  grpc::Status GetUploadStatus(grpc::ServerContext* call, const v1::GetUploadStatusRequest* request,
                               v1::UploadStatus* reply) override;
  grpc::Status FinalizeSurvey(grpc::ServerContext* call, const v1::FinalizeSurveyRequest* request, v1::Survey* reply) override;
  grpc::Status GetSurvey(grpc::ServerContext* call, const v1::GetSurveyRequest* request, v1::Survey* reply) override;
  grpc::Status ListSurveys(grpc::ServerContext* call, const v1::ListSurveysRequest* request,
                           v1::ListSurveysResponse* reply) override;
  grpc::Status DeleteSurvey(grpc::ServerContext* call, const v1::DeleteSurveyRequest* request,
                            v1::DeleteSurveyResponse* reply) override;

 private:
  void describe(const storage::SurveyRecord& survey, bool details, v1::Survey* reply);

  ServiceContext& context_;
  std::filesystem::path scratch_;  // where FinalizeSurvey copies a bundle to parse it
  // Each upload stream holds a server thread and a pool connection per chunk; each finalize a
  // copy of the survey on the scratch disk and a pool connection: one tenant's dozens of them
  // slowed every other tenant's calls to seconds (issue 37).
  StreamSlots upload_slots_;
  StreamSlots finalize_slots_;
  FilesBeingWritten files_being_written_;
};

}  // namespace bathyslam::server
