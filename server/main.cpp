// bathyslam-server: the survey, job and map services (gRPC, with health checking and
// reflection) and a scheduler of job workers, in front of PostgreSQL (checked for a schema this
// binary understands at start). `bathyslam-server migrate` brings a database's schema up to
// date; `bathyslam-server token` issues an API token.
#include <unistd.h>

#include <charconv>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/impl/server_builder_option.h>
#include <grpcpp/impl/server_builder_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/grpcpp.h>

#include "core/types/format.h"
#include "server/database_health.h"
#include "server/http/http_api.h"
#include "server/log.h"
#include "server/scheduler/scheduler.h"
#include "server/scratch_dir.h"
#include "server/services/job_service.h"
#include "server/services/map_service.h"
#include "server/services/site_service.h"
#include "server/services/survey_service.h"
#include "server/services/token_gate.h"
#include "server/storage/migrations.h"

namespace {

namespace storage = bathyslam::storage;
namespace service = bathyslam::server;

int run_migrate(const std::string& db) {
  storage::Connection connection(db);
  const int known = storage::embedded_migrations().back().version;
  const int before = storage::schema_version(connection);
  if (before > known) {
    std::fprintf(stderr, "bathyslam-server migrate: the database is at schema version %d, newer than this binary (%d)\n",
                 before, known);
    return 1;
  }
  const std::vector<int> applied = storage::migrate(connection);
  for (int version : applied) std::printf("applied migration %04d\n", version);
  std::printf("schema at version %d (%zu applied)\n", storage::schema_version(connection), applied.size());
  return 0;
}

// The tenant called `name`, created on first use.
std::int64_t tenant_named(storage::ConnectionPool& pool, storage::SurveyStore& surveys, const std::string& name) {
  {
    auto connection = pool.acquire();  // given back before create_tenant borrows one
    storage::Result row = connection->exec("SELECT id FROM tenants WHERE name = $1", {name});
    if (row.rows() == 1) return row.int64(0, "id");
  }
  return surveys.create_tenant(name);
}

struct QuotaOptions {
  std::string tenant;
  std::int64_t bytes = -1;  // -1: the option left out
  bool none = false;
};

// `tenant quota`: sets the tenant's storage quota (or removes it), then shows its use; without
// --bytes or --none only shows it.
int tenant_quota(const std::string& db, const QuotaOptions& q) {
  storage::ConnectionPool pool(db, 1);
  storage::SurveyStore surveys(pool);
  std::int64_t tenant = 0;
  {
    auto connection = pool.acquire();
    storage::Result row = connection->exec("SELECT id FROM tenants WHERE name = $1", {q.tenant});
    if (row.rows() == 0) {  // a typo must not make a tenant
      std::fprintf(stderr, "bathyslam-server tenant quota: no tenant named '%s' (token create makes one)\n", q.tenant.c_str());
      return 1;
    }
    tenant = row.int64(0, "id");
  }
  if (q.none) surveys.set_quota(tenant, std::nullopt);
  else if (q.bytes >= 0) surveys.set_quota(tenant, q.bytes);
  const storage::StorageUse use = surveys.storage_use(tenant);
  std::printf("tenant %s: %lld bytes stored, quota %s\n", q.tenant.c_str(), static_cast<long long>(use.stored_bytes),
              use.quota_bytes ? (std::to_string(*use.quota_bytes) + " bytes").c_str() : "none");
  return 0;
}

struct TokenOptions {
  std::string tenant, description, token;
  std::int64_t id = 0;
  double expires_in_days = 0;  // 0: the option left out, never (a 0 given is refused)
};

// --expires-in-days: more than 0 and at most 100 years. 0 is refused rather than read as "never"
// (issue_token's 0) or as "at once": leaving the option out says never, and revoke ends a token now.
std::string expiry_days_problem(const std::string& text) {
  double days = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), days);
  if (error != std::errc() || end != text.data() + text.size() || !(days > 0 && days <= 36500))
    return text + " is not a number of days in (0, 36500]; leave the option out for a token that never expires";
  return "";
}

int create_token(const std::string& db, const TokenOptions& t) {
  if (t.tenant.empty()) {
    std::fprintf(stderr, "bathyslam-server token create: --tenant is required\n");
    return 2;
  }
  storage::ConnectionPool pool(db, 1);
  storage::SurveyStore surveys(pool);
  std::printf("%s\n",
              surveys.issue_token(tenant_named(pool, surveys, t.tenant), t.description, t.expires_in_days * 86400).c_str());
  return 0;
}

int revoke_token(const std::string& db, const TokenOptions& t) {
  if ((t.id > 0) == !t.token.empty()) {
    std::fprintf(stderr, "bathyslam-server token revoke: give either --id (from token list) or --token\n");
    return 2;
  }
  storage::ConnectionPool pool(db, 1);
  storage::SurveyStore surveys(pool);
  if (t.id > 0 ? surveys.revoke_token(t.id) : surveys.revoke_token(t.token)) {
    std::printf("revoked\n");
    return 0;
  }
  std::fprintf(stderr, "bathyslam-server token revoke: no such token, or revoked already\n");
  return 1;
}

std::string utc(double seconds) { return bathyslam::format_utc(seconds, "%Y-%m-%dT%H:%M:%SZ"); }

int list_tokens(const std::string& db, const TokenOptions& t) {
  storage::ConnectionPool pool(db, 1);
  storage::SurveyStore surveys(pool);
  std::printf("%6s  %-20s  %-20s  %-20s  %-20s  %s\n", "id", "tenant", "created", "expires", "revoked", "description");
  for (const storage::TokenInfo& token : surveys.list_tokens(t.tenant.empty() ? std::nullopt : std::optional(t.tenant)))
    std::printf("%6lld  %-20s  %-20s  %-20s  %-20s  %s\n", static_cast<long long>(token.id), token.tenant.c_str(),
                utc(token.created_at).c_str(), token.expires_at ? utc(*token.expires_at).c_str() : "never",
                token.revoked_at ? utc(*token.revoked_at).c_str() : "-", token.description.c_str());
  return 0;
}

// Removes gRPC's reflection plugin from a server builder.
class WithoutReflection : public grpc::ServerBuilderOption {
 public:
  void UpdateArguments(grpc::ChannelArguments*) override {}
  void UpdatePlugins(std::vector<std::unique_ptr<grpc::ServerBuilderPlugin>>* plugins) override {
    std::erase_if(*plugins, [](const auto& plugin) { return plugin->name() == "proto_server_reflection"; });
  }
};

struct ServeOptions {
  std::string listen;
  std::string db;
  bool migrate = false;
  int workers = 1;
  std::string dev_tenant;
  bool reflection = false;
  std::string scratch;
  int lease_seconds = 30;
  int statement_timeout_seconds = 60;
  std::string tls_cert, tls_key, tls_client_ca;  // PEM files; no certificate: plaintext
  std::string http;  // HOST:PORT of the HTTP endpoint; empty: none
  // gRPC's threads: each call in progress holds one (a WatchJob or upload stream for its whole
  // life, up to 64 + 8 + 2 a tenant); a burst of 4,000 refused WatchJob calls made 1,928 under a
  // bound of 2,048 (bench/fairness.sh, docs/service.md). Past the bound a call is refused
  // RESOURCE_EXHAUSTED, so threads and memory stay bounded whatever the clients do.
  int max_threads = 512;
  service::Limits limits;
};

// --http's HOST:PORT (a bare PORT is on the loopback interface).
bathyslam::server::http::HttpOptions http_options(const ServeOptions& o) {
  bathyslam::server::http::HttpOptions h{.tls_cert = o.tls_cert, .tls_key = o.tls_key, .tls_client_ca = o.tls_client_ca};
  const std::size_t colon = o.http.rfind(':');
  if (colon != std::string::npos) h.host = o.http.substr(0, colon);
  const std::string port = colon == std::string::npos ? o.http : o.http.substr(colon + 1);
  const auto [end, error] = std::from_chars(port.data(), port.data() + port.size(), h.port);
  if (error != std::errc() || end != port.data() + port.size() || h.port < 0 || h.port > 65535 || h.host.empty())
    throw std::runtime_error("--http: expected HOST:PORT (port 0: any free port), not '" + o.http + "'");
  return h;
}

std::string read_pem(const std::string& option, const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(option + ": cannot read " + path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// TLS when a certificate is given; with a client CA, clients must present a certificate it signed.
std::shared_ptr<grpc::ServerCredentials> server_credentials(const ServeOptions& o) {
  if (o.tls_cert.empty() != o.tls_key.empty()) throw std::runtime_error("--tls-cert and --tls-key go together");
  if (o.tls_cert.empty()) {
    if (!o.tls_client_ca.empty()) throw std::runtime_error("--tls-client-ca needs --tls-cert and --tls-key");
    return grpc::InsecureServerCredentials();
  }
  grpc::SslServerCredentialsOptions options(o.tls_client_ca.empty()
                                                ? GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE
                                                : GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
  options.pem_key_cert_pairs.push_back({read_pem("--tls-key", o.tls_key), read_pem("--tls-cert", o.tls_cert)});
  if (!o.tls_client_ca.empty()) options.pem_root_certs = read_pem("--tls-client-ca", o.tls_client_ca);
  return grpc::SslServerCredentials(options);
}

int serve(const ServeOptions& o) {
  // Refused before anything starts: a bad --http value must not leave a server half up.
  std::optional<bathyslam::server::http::HttpOptions> http_config;
  if (!o.http.empty()) http_config = http_options(o);
  // Block the stop signals before any thread starts, so every thread inherits the mask; one
  // thread waits for them and shuts down cleanly.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  storage::ConnectionPool pool(o.db, static_cast<std::size_t>(8 + 2 * o.workers),
                               {.statement_timeout = std::chrono::seconds(o.statement_timeout_seconds)});
  storage::SurveyStore surveys(pool);
  storage::JobQueue jobs(pool, {std::chrono::seconds(o.lease_seconds), std::chrono::seconds(5)});
  storage::ResultStore results(pool);
  storage::SiteStore sites(pool);
  service::ServiceContext context{surveys, jobs, results, sites, o.limits, std::nullopt};
  if (!o.dev_tenant.empty()) context.dev_tenant = tenant_named(pool, surveys, o.dev_tenant);
  const std::filesystem::path temp = std::filesystem::temp_directory_path();
  const std::filesystem::path scratch =
      o.scratch.empty() ? service::default_scratch_root(temp, getpid()) : std::filesystem::path(o.scratch);
  if (o.scratch.empty()) {
    if (const int removed = service::remove_dead_servers_scratch(temp))
      service::log("removed the scratch folders of %d servers no longer running", removed);
  }
  service::SurveyService survey_service(context, scratch);
  service::JobEventBell job_event_bell(o.db);
  service::JobService job_service(context, job_event_bell);
  service::MapService map_service(context);
  service::SiteService site_service(context);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(o.listen, server_credentials(o), &port);
  // Reflection is served on a development server (a dev tenant) or when the operator asks for
  // it (linking it registers it everywhere), and asks for the API's token like every service
  // but health: its own service asks for none.
  if (!o.reflection && o.dev_tenant.empty()) {
    builder.SetOption(std::make_unique<WithoutReflection>());
  } else {
    std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> gates;
    gates.push_back(std::make_unique<service::TokenGateFactory>(context, "/grpc.reflection."));
    builder.experimental().SetInterceptorCreators(std::move(gates));
  }
  builder.RegisterService(&survey_service);
  builder.RegisterService(&job_service);
  builder.RegisterService(&map_service);
  builder.RegisterService(&site_service);
  builder.SetMaxReceiveMessageSize(2 << 20);  // a 1 MiB chunk and its envelope
  grpc::ResourceQuota quota("bathyslam-server");
  quota.SetMaxThreads(o.max_threads);
  builder.SetResourceQuota(quota);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server || port == 0) {
    std::fprintf(stderr, "bathyslam-server: cannot listen on %s\n", o.listen.c_str());
    return 1;
  }
  char host[256] = "bathyslam";
  gethostname(host, sizeof host - 1);
  service::Scheduler scheduler(surveys, jobs, results,
                              {.workers = o.workers, .name = std::string(host) + ":" + std::to_string(getpid()),
                               .scratch = scratch,
                               // Three heartbeats per lease: one lost to a slow database does not lose the job.
                               .heartbeat = std::min<std::chrono::milliseconds>(std::chrono::seconds(5),
                                                                                std::chrono::seconds(o.lease_seconds) / 3),
                               .retry = {}, .max_map_cells = o.limits.max_map_cells});
  scheduler.start();
  service::DatabaseHealth database_health(o.db, server->GetHealthCheckService(), std::chrono::seconds(1));
  std::unique_ptr<bathyslam::server::http::HttpApi> http;
  if (http_config) http = std::make_unique<bathyslam::server::http::HttpApi>(context, job_event_bell, *http_config);
  std::thread stopper([&] {
    int signal = 0;
    sigwait(&stop_signals, &signal);
    service::log("signal %d, shutting down", signal);
    server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(5));
  });
  // The port actually bound (":0" asks for any free one): tests and scripts read it here.
  const std::string address = o.listen.substr(0, o.listen.rfind(':')) + ":" + std::to_string(port);
  std::printf("bathyslam-server listening on %s\n", address.c_str());
  if (http) std::printf("bathyslam-server http on %s://%s:%d\n", o.tls_cert.empty() ? "http" : "https", http_config->host.c_str(), http->port());
  std::fflush(stdout);
  service::log("listening on %s; %d workers; %s", address.c_str(), o.workers,
              context.dev_tenant ? ("callers without a token act as tenant '" + o.dev_tenant + "'").c_str()
                                 : "an API token is required");
  server->Wait();
  stopper.join();
  http.reset();
  scheduler.stop();
  std::error_code ignored;
  if (o.scratch.empty()) std::filesystem::remove_all(scratch, ignored);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bathyslam-server: the bathyslam gRPC service"};
  ServeOptions o;
  o.listen = "127.0.0.1:50051";
  app.add_option("--listen", o.listen, "address to listen on (port 0: any free port)")->capture_default_str()
      ->envname("BATHYSLAM_LISTEN");
  auto add_db_option = [&o](CLI::App* command) {
    command->add_option("--db", o.db, "PostgreSQL connection string (libpq keywords or a postgresql:// URI)")
        ->envname("BATHYSLAM_DB");
  };
  add_db_option(&app);
  app.add_flag("--migrate", o.migrate, "apply pending schema migrations at start");
  app.add_option("--workers", o.workers, "job workers (0: serve the API only)")->capture_default_str()
      ->check(CLI::Range(0, 256))->envname("BATHYSLAM_WORKERS");
  app.add_option("--dev-tenant", o.dev_tenant, "callers without a token act as this tenant (created if needed)")
      ->envname("BATHYSLAM_DEV_TENANT");
  app.add_flag("--reflection", o.reflection, "serve gRPC reflection without a dev tenant too (to callers with a token)");
  app.add_option("--scratch", o.scratch,
                 "folder for survey copies while a job or a validation reads them (default: $TMPDIR/bathyslam-server-<pid>,\n"
                 "removed at exit, and by the next server if this one is killed)");
  app.add_option("--lease-seconds", o.lease_seconds, "job lease; a worker that stops renewing loses its job")
      ->capture_default_str()->check(CLI::Range(5, 3600));
  app.add_option("--tls-cert", o.tls_cert, "PEM certificate (chain): serve TLS")->envname("BATHYSLAM_TLS_CERT");
  app.add_option("--tls-key", o.tls_key, "PEM private key of --tls-cert")->envname("BATHYSLAM_TLS_KEY");
  app.add_option("--tls-client-ca", o.tls_client_ca, "PEM CA: require client certificates it signed (mutual TLS)");
  app.add_option("--http", o.http,
                 "HOST:PORT (or PORT, on 127.0.0.1) of an HTTP endpoint serving surveys, jobs, reports and maps\n"
                 "(COG by range requests) with the same tokens; TLS as for gRPC; port 0: any free port")
      ->envname("BATHYSLAM_HTTP");
  app.add_option("--statement-timeout", o.statement_timeout_seconds,
                 "seconds after which PostgreSQL cancels a statement of a request or a job")
      ->capture_default_str()->check(CLI::Range(1, 3600));
  app.add_option("--max-file-bytes", o.limits.max_file_bytes, "largest uploaded file")->capture_default_str();
  app.add_option("--max-map-cells", o.limits.max_map_cells, "cells of one survey's map at its resolution; larger surveys are refused")
      ->capture_default_str();
  app.add_option("--max-active-jobs", o.limits.max_active_jobs, "queued and running jobs per tenant")
      ->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--max-watch-streams", o.limits.max_watch_streams, "open WatchJob streams per tenant on this server")
      ->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--max-upload-streams", o.limits.max_upload_streams, "UploadFile streams in progress per tenant on this server")
      ->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--max-finalizes", o.limits.max_finalizes, "FinalizeSurvey calls in progress per tenant on this server")
      ->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--max-http-requests", o.limits.max_http_requests,
                 "HTTP requests in progress per tenant on this server (a download or event stream until its end)")
      ->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--max-threads", o.max_threads,
                 "gRPC threads, one per call in progress; calls beyond are refused (RESOURCE_EXHAUSTED)")
      ->capture_default_str()->check(CLI::Range(16, 1 << 16));
  app.add_option("--max-attempts", o.limits.max_attempts, "runs of a job whose worker died")
      ->capture_default_str()->check(CLI::Range(1, 10));
  CLI::App* migrate = app.add_subcommand("migrate", "apply pending schema migrations and exit");
  add_db_option(migrate);  // `migrate --db ...` as well as `--db ... migrate`
  CLI::App* token = app.add_subcommand("token", "API tokens: create (the default), revoke, list");
  add_db_option(token);
  TokenOptions t;
  token->add_option("--tenant", t.tenant, "tenant name (token --tenant NAME: the same as token create)");
  token->add_option("--description", t.description, "what the token is for");
  CLI::App* create = token->add_subcommand("create", "issue a token for a tenant (created if needed) and print it");
  add_db_option(create);
  create->add_option("--tenant", t.tenant, "tenant name")->required();
  create->add_option("--description", t.description, "what the token is for");
  create->add_option("--expires-in-days", t.expires_in_days,
                     "refuse the token after this many days: more than 0 (fractions allowed), at most 36500; "
                     "without it the token never expires")
      ->check(CLI::Validator(expiry_days_problem, "DAYS in (0, 36500]"));
  CLI::App* revoke = token->add_subcommand("revoke", "revoke a token: it is refused from now on");
  add_db_option(revoke);
  revoke->add_option("--id", t.id, "the token's id, from token list");
  revoke->add_option("--token", t.token, "the token itself");
  CLI::App* list = token->add_subcommand("list", "every token (never the secret), or a tenant's");
  add_db_option(list);
  list->add_option("--tenant", t.tenant, "only this tenant's");
  CLI::App* tenant = app.add_subcommand("tenant", "tenants: quota (storage)");
  tenant->require_subcommand(1);
  QuotaOptions q;
  CLI::App* quota = tenant->add_subcommand("quota", "show a tenant's storage, or set its quota: the bytes its uploads may hold");
  add_db_option(quota);
  quota->add_option("--tenant", q.tenant, "tenant name")->required();
  auto* bytes = quota->add_option("--bytes", q.bytes, "the quota in bytes")->check(CLI::NonNegativeNumber);
  quota->add_flag("--none", q.none, "no quota")->excludes(bytes);
  CLI11_PARSE(app, argc, argv);
  if (o.db.empty()) {
    std::fprintf(stderr, "bathyslam-server: no database; pass --db or set BATHYSLAM_DB\n");
    return 2;
  }
  try {
    if (*migrate) return run_migrate(o.db);
    {
      storage::Connection connection(o.db);
      storage::ensure_schema(connection, o.migrate);
    }
    if (*quota) return tenant_quota(o.db, q);
    if (*revoke) return revoke_token(o.db, t);
    if (*list) return list_tokens(o.db, t);
    if (*token) return create_token(o.db, t);
    return serve(o);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bathyslam-server: %s\n", error.what());
    return 1;
  }
}
