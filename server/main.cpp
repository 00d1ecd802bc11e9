// bathyslam-server: a gRPC server with health checking and reflection, in front of PostgreSQL
// (checked for a schema this binary understands at start); the survey, job and map services
// arrive with the service issues. `bathyslam-server migrate` brings a database's schema up to date.
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/grpcpp.h>

#include "server/storage/migrations.h"

namespace {

namespace storage = bathyslam::storage;

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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bathyslam-server: the bathyslam gRPC service"};
  std::string listen = "127.0.0.1:50051";
  app.add_option("--listen", listen, "address to listen on")->capture_default_str()
      ->envname("BATHYSLAM_LISTEN");
  std::string db;
  auto add_db_option = [&db](CLI::App* command) {
    command->add_option("--db", db, "PostgreSQL connection string (libpq keywords or a postgresql:// URI)")
        ->envname("BATHYSLAM_DB");
  };
  add_db_option(&app);
  bool apply_migrations = false;
  app.add_flag("--migrate", apply_migrations, "apply pending schema migrations at start");
  CLI::App* migrate = app.add_subcommand("migrate", "apply pending schema migrations and exit");
  add_db_option(migrate);  // `migrate --db ...` as well as `--db ... migrate`
  CLI11_PARSE(app, argc, argv);
  if (db.empty()) {
    std::fprintf(stderr, "bathyslam-server: no database; pass --db or set BATHYSLAM_DB\n");
    return 2;
  }
  try {
    if (*migrate) return run_migrate(db);
    storage::Connection connection(db);
    storage::ensure_schema(connection, apply_migrations);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bathyslam-server: %s\n", error.what());
    return 1;
  }

  // Block the stop signals in every thread; one thread waits for them and shuts down cleanly.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(listen, grpc::InsecureServerCredentials(), &port);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server || port == 0) {
    std::fprintf(stderr, "bathyslam-server: cannot listen on %s\n", listen.c_str());
    return 1;
  }
  std::thread stopper([&] {
    int signal = 0;
    sigwait(&stop_signals, &signal);
    std::printf("bathyslam-server: signal %d, shutting down\n", signal);
    server->Shutdown();
  });
  std::printf("bathyslam-server listening on %s\n", listen.c_str());
  std::fflush(stdout);
  server->Wait();
  stopper.join();
  return 0;
}
