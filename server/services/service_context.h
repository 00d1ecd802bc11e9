#pragma once
// What every service handler needs: the stores, the caller's tenant, the limits, and the
// translation of refusals into gRPC statuses that name the field at fault.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "server/services/stream_slots.h"
#include "server/storage/job_queue.h"
#include "server/storage/result_store.h"
#include "server/storage/site_store.h"
#include "server/storage/survey_store.h"

namespace bathyslam::server {

struct Limits {
  std::int64_t max_file_bytes = std::int64_t{8} << 30;  // one uploaded file
  int max_active_jobs = 16;                              // queued + running, per tenant
  int max_watch_streams = 64;                            // open WatchJob streams per tenant, per server
  int max_upload_streams = 8;                            // UploadFile streams in progress per tenant, per server
  int max_finalizes = 2;                                 // FinalizeSurvey calls in progress per tenant, per server
  // HTTP requests in progress per tenant, per server: half the endpoint's 32 threads (an event
  // stream or a download holds one until its last byte).
  int max_http_requests = 16;
  int max_attempts = 2;                                  // per job: a crashed worker's job runs once more
  // Cells of one survey's map (1e8: 5 km × 5 km at 0.5 m, 1.2 GB for its three float bands).
  std::uint64_t max_map_cells = 100'000'000;
};

struct ServiceContext {
  storage::SurveyStore& surveys;
  storage::JobQueue& jobs;
  storage::ResultStore& results;
  storage::SiteStore& sites;
  Limits limits;
  // Callers without a token act as this tenant (--dev-tenant); nullopt: a token is required.
  std::optional<std::int64_t> dev_tenant;
};

// A refusal with its status code, thrown by handlers and turned into the response status.
class Refusal : public std::runtime_error {
 public:
  Refusal(grpc::StatusCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  grpc::StatusCode code() const { return code_; }

 private:
  grpc::StatusCode code_;
};

// A slot of `slots` for the tenant's call, or RESOURCE_EXHAUSTED naming the limit: "this tenant
// has N <held>, the limit (<flag>); <advice>".
StreamSlots::Slot slot_or_refuse(StreamSlots& slots, std::int64_t tenant, const std::string& held, const std::string& flag,
                                 const std::string& advice);

// INVALID_ARGUMENT "field: message".
Refusal invalid(const std::string& field, const std::string& message);

// The longest survey name, in bytes: well under what PostgreSQL's unique index on names can
// hold (about 2.7 kB a row), so that a long name is the client's error, not the database's.
inline constexpr std::size_t kMaxNameBytes = 255;

// Surveys one job may join (issue 33: 20 surveys of one site in one job).
inline constexpr int kMaxSiteSurveys = 20;

// Text a request carries that the server stores, looks up or passes on: refused with
// INVALID_ARGUMENT naming `field` when it holds a NUL byte, which libpq and PostgreSQL would cut
// it at (or refuse), so that "nav.csv\0x" never answers for "nav.csv".
void check_text(const std::string& field, std::string_view text);
// A name people read (a survey's, a parameter's): besides check_text, at most `max_bytes`, UTF-8,
// and no control characters (a newline in a name would break every listing and log line it is in).
void check_name(const std::string& field, std::string_view name, std::size_t max_bytes = kMaxNameBytes);
// A list's optional filter by name (ListSurveys, ListSites): nullopt when empty, else checked as a name.
std::optional<std::string> name_filter(const std::string& field, const std::string& name);

// The tenant of the caller: `authorization: Bearer <token>` metadata, or the dev tenant.
// UNAUTHENTICATED otherwise.
std::int64_t caller_tenant(const ServiceContext& context, const grpc::ServerContextBase& call);
// The same from the authorization header's value (nullptr: none sent), for HTTP as for gRPC.
std::int64_t tenant_of_authorization(const ServiceContext& context, const std::string* authorization);

// The survey / job if it exists and belongs to the tenant; NOT_FOUND otherwise (another
// tenant's ids are indistinguishable from unknown ones).
storage::SurveyRecord owned_survey(ServiceContext& context, std::int64_t tenant, std::int64_t survey_id,
                                   const std::string& field = "survey_id");
storage::JobRecord owned_job(ServiceContext& context, std::int64_t tenant, std::int64_t job_id);
storage::SiteRecord owned_site(ServiceContext& context, std::int64_t tenant, std::int64_t site_id);
// owned_job for the calls that serve a job's results (map, tiles, trajectory, report): a
// cancelled job's are never served, FAILED_PRECONDITION, whatever a cancel during the store
// stage left behind until its worker removes it.
storage::JobRecord job_with_results(ServiceContext& context, std::int64_t tenant, std::int64_t job_id);

// Page sizes (0 means 100, at most 1000) and page tokens (an id as decimal text).
int page_size(int requested);
std::int64_t page_token(const std::string& token);
// A list read with one row more than `size` trimmed to the page: true when a next page exists
// (its token is then the last row's id).
template <typename Row>
bool trim_to_page(std::vector<Row>& rows, int size) {
  const bool more = static_cast<int>(rows.size()) > size;
  if (more) rows.resize(static_cast<std::size_t>(size));
  return more;
}

// Runs a handler: Refusal becomes its status; a transient database failure UNAVAILABLE (a lost
// serialization race ABORTED), saying the cause in words; a scratch file the disk refused
// (WriteError) RESOURCE_EXHAUSTED when it is full, else UNAVAILABLE; any other failure INTERNAL. Whatever
// the server itself failed at is logged whole and never sent: SQL states, PostgreSQL's messages
// and server paths stay in the log. A call past its deadline is DEADLINE_EXCEEDED.
grpc::Status handle(const char* method, grpc::ServerContext* call, const std::function<void()>& body);
// handle() without a call to check: the status alone (the HTTP endpoint's handlers).
grpc::Status status_of(const char* method, const std::function<void()>& body);

}  // namespace bathyslam::server
