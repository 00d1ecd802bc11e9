#include "server/services/service_context.h"

#include <charconv>

#include "core/io/file_bytes.h"
#include "core/io/problem.h"
#include "server/log.h"

namespace bathyslam::server {

Refusal invalid(const std::string& field, const std::string& message) {
  return Refusal(grpc::StatusCode::INVALID_ARGUMENT, field + ": " + message);
}

void check_text(const std::string& field, std::string_view text) {
  if (const std::size_t nul = text.find('\0'); nul != std::string_view::npos)
    throw invalid(field, "holds a NUL byte (at byte " + std::to_string(nul) + "): " + quoted_input(text));
}

void check_name(const std::string& field, std::string_view name, std::size_t max_bytes) {
  check_text(field, name);
  if (name.size() > max_bytes)
    throw invalid(field, "at most " + std::to_string(max_bytes) + " bytes, not " + std::to_string(name.size()) + ": " +
                             quoted_input(name));
  // printable() changes exactly the control characters and the bytes that are not UTF-8.
  if (printable(name) != name) throw invalid(field, "must be UTF-8 without control characters: " + quoted_input(name));
}

std::optional<std::string> name_filter(const std::string& field, const std::string& name) {
  if (name.empty()) return std::nullopt;
  check_name(field, name);
  return name;
}

std::int64_t caller_tenant(const ServiceContext& context, const grpc::ServerContextBase& call) {
  const auto& metadata = call.client_metadata();
  const auto header = metadata.find("authorization");
  if (header == metadata.end()) return tenant_of_authorization(context, nullptr);
  const std::string value(header->second.data(), header->second.size());
  return tenant_of_authorization(context, &value);
}

std::int64_t tenant_of_authorization(const ServiceContext& context, const std::string* authorization) {
  if (!authorization) {
    if (context.dev_tenant) return *context.dev_tenant;
    throw Refusal(grpc::StatusCode::UNAUTHENTICATED, "authorization: send 'Bearer <token>' (bathyslam-server token)");
  }
  constexpr std::string_view kBearer = "Bearer ";
  if (authorization->rfind(kBearer, 0) != 0)
    throw Refusal(grpc::StatusCode::UNAUTHENTICATED, "authorization: expected 'Bearer <token>'");
  if (auto tenant = context.surveys.tenant_of_token(authorization->substr(kBearer.size()))) return *tenant;
  throw Refusal(grpc::StatusCode::UNAUTHENTICATED, "authorization: unknown or revoked token");
}

storage::SurveyRecord owned_survey(ServiceContext& context, std::int64_t tenant, std::int64_t survey_id,
                                   const std::string& field) {
  if (survey_id <= 0) throw invalid(field, "must be positive");
  auto survey = context.surveys.survey(survey_id);
  if (!survey || survey->tenant_id != tenant)
    throw Refusal(grpc::StatusCode::NOT_FOUND, field + ": no survey " + std::to_string(survey_id));
  return *survey;
}

storage::SiteRecord owned_site(ServiceContext& context, std::int64_t tenant, std::int64_t site_id) {
  if (site_id <= 0) throw invalid("site_id", "must be positive");
  auto site = context.sites.site(site_id);
  if (!site || site->tenant_id != tenant) throw Refusal(grpc::StatusCode::NOT_FOUND, "site_id: no site " + std::to_string(site_id));
  return *site;
}

storage::JobRecord owned_job(ServiceContext& context, std::int64_t tenant, std::int64_t job_id) {
  if (job_id <= 0) throw invalid("job_id", "must be positive");
  auto job = context.jobs.job(job_id);
  if (!job || job->tenant_id != tenant) throw Refusal(grpc::StatusCode::NOT_FOUND, "job_id: no job " + std::to_string(job_id));
  return *job;
}

storage::JobRecord job_with_results(ServiceContext& context, std::int64_t tenant, std::int64_t job_id) {
  storage::JobRecord job = owned_job(context, tenant, job_id);
  if (job.state == storage::JobState::kCancelled)
    throw Refusal(grpc::StatusCode::FAILED_PRECONDITION,
                  "job_id: job " + std::to_string(job.id) + " was cancelled; its results are not kept");
  return job;
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
    throw invalid("page_token", quoted_input(token) + " is not a token this server gave");
  return id;
}

namespace {

// What a client may know of a database failure: its cause in words, never PostgreSQL's message
// (it may name a socket path, a data file or a constraint) nor the SQL state.
std::string database_cause(const storage::DatabaseError& error) {
  const std::string& state = error.sqlstate();
  if (state == "53300") return "every database connection is in use";
  if (state.starts_with("53")) return "the database is out of resources";
  if (state.starts_with("57P")) return "the database is shutting down or starting";
  return "the database cannot be reached";
}

grpc::Status database_failure(const char* method, const storage::DatabaseError& error) {
  log("%s: %s", method, error.what());
  if (error.sqlstate() == "40001" || error.sqlstate() == "40P01")
    return grpc::Status(grpc::StatusCode::ABORTED, "a concurrent change collided with this call; try it again");
  if (error.transient())
    return grpc::Status(grpc::StatusCode::UNAVAILABLE, "database: " + database_cause(error) + "; try again later");
  return grpc::Status(grpc::StatusCode::INTERNAL, std::string(method) + ": the server failed; its log has the details");
}

// A scratch file the disk refused: the server's shortage, never a verdict on the request's data
// (FinalizeSurvey stores none). The path stays in the log.
grpc::Status write_failure(const char* method, const WriteError& error) {
  log("%s: %s", method, error.what());
  if (error.out_of_space())
    return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                        "the server's scratch space is full; nothing was stored, try again later");
  return grpc::Status(grpc::StatusCode::UNAVAILABLE,
                      "the server could not write its scratch files; nothing was stored, try again later");
}

}  // namespace

grpc::Status handle(const char* method, grpc::ServerContext* call, const std::function<void()>& body) {
  grpc::Status status = status_of(method, body);
  if (status.ok() && call->IsCancelled())
    return grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, "the call ended before the reply");
  return status;
}

grpc::Status status_of(const char* method, const std::function<void()>& body) {
  try {
    body();
    return grpc::Status::OK;
  } catch (const Refusal& refusal) {
    return grpc::Status(refusal.code(), refusal.what());
  } catch (const storage::DatabaseError& error) {
    return database_failure(method, error);
  } catch (const WriteError& error) {
    return write_failure(method, error);
  } catch (const std::exception& error) {
    log("%s: %s", method, error.what());
    return grpc::Status(grpc::StatusCode::INTERNAL, std::string(method) + ": the server failed; its log has the details");
  } catch (...) {  // gRPC's thread would end the process
    log("%s: unknown exception", method);
    return grpc::Status(grpc::StatusCode::INTERNAL, "unknown error");
  }
}

StreamSlots::Slot slot_or_refuse(StreamSlots& slots, std::int64_t tenant, const std::string& held, const std::string& flag,
                                 const std::string& advice) {
  std::optional<StreamSlots::Slot> slot = slots.take(tenant);
  if (!slot) {
    throw Refusal(grpc::StatusCode::RESOURCE_EXHAUSTED, "this tenant has " + std::to_string(slots.per_tenant()) + " " +
                                                            held + ", the limit (" + flag + "); " + advice);
  }
  return std::move(*slot);
}

}  // namespace bathyslam::server
