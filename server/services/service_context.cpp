#include "server/services/service_context.h"

#include <charconv>

#include "server/log.h"

namespace bathyslam::server {

Refusal invalid(const std::string& field, const std::string& message) {
  return Refusal(grpc::StatusCode::INVALID_ARGUMENT, field + ": " + message);
}

std::int64_t caller_tenant(const ServiceContext& context, const grpc::ServerContextBase& call) {
  const auto& metadata = call.client_metadata();
  const auto header = metadata.find("authorization");
  if (header == metadata.end()) {
    if (context.dev_tenant) return *context.dev_tenant;
    throw Refusal(grpc::StatusCode::UNAUTHENTICATED, "authorization: send 'Bearer <token>' (bathyslam-server token)");
  }
  const std::string value(header->second.data(), header->second.size());
  constexpr std::string_view kBearer = "Bearer ";
  if (value.rfind(kBearer, 0) != 0)
    throw Refusal(grpc::StatusCode::UNAUTHENTICATED, "authorization: expected 'Bearer <token>'");
  if (auto tenant = context.surveys.tenant_of_token(value.substr(kBearer.size()))) return *tenant;
  throw Refusal(grpc::StatusCode::UNAUTHENTICATED, "authorization: unknown or revoked token");
}

storage::SurveyRecord owned_survey(ServiceContext& context, std::int64_t tenant, std::int64_t survey_id) {
  if (survey_id <= 0) throw invalid("survey_id", "must be positive");
  auto survey = context.surveys.survey(survey_id);
  if (!survey || survey->tenant_id != tenant)
    throw Refusal(grpc::StatusCode::NOT_FOUND, "survey_id: no survey " + std::to_string(survey_id));
  return *survey;
}

storage::JobRecord owned_job(ServiceContext& context, std::int64_t tenant, std::int64_t job_id) {
  if (job_id <= 0) throw invalid("job_id", "must be positive");
  auto job = context.jobs.job(job_id);
  if (!job || job->tenant_id != tenant) throw Refusal(grpc::StatusCode::NOT_FOUND, "job_id: no job " + std::to_string(job_id));
  return *job;
}

int page_size(int requested) {
  if (requested < 0 || requested > 1000) throw invalid("page_size", "must be within 0..1000 (0: 100)");
  return requested == 0 ? 100 : requested;
}

std::int64_t page_token(const std::string& token) {
  if (token.empty()) return 0;
  std::int64_t id = 0;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), id);
  if (error != std::errc() || end != token.data() + token.size() || id <= 0)
    throw invalid("page_token", "'" + token + "' is not a token this server gave");
  return id;
}

grpc::Status handle(const char* method, grpc::ServerContext* call, const std::function<void()>& body) {
  try {
    body();
    if (call->IsCancelled()) return grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, "the call ended before the reply");
    return grpc::Status::OK;
  } catch (const Refusal& refusal) {
    return grpc::Status(refusal.code(), refusal.what());
  } catch (const storage::DatabaseError& error) {
    log("%s: database: %s", method, error.what());
    return grpc::Status(grpc::StatusCode::UNAVAILABLE, std::string("database: ") + error.what());
  } catch (const std::exception& error) {
    log("%s: %s", method, error.what());
    return grpc::Status(grpc::StatusCode::INTERNAL, error.what());
  } catch (...) {  // gRPC's thread would end the process
    log("%s: unknown exception", method);
    return grpc::Status(grpc::StatusCode::INTERNAL, "unknown error");
  }
}

}  // namespace bathyslam::server
