// bathyslam-server: for now a gRPC server with health checking and reflection only; the survey,
// job and map services arrive with the persistence and service issues.
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/grpcpp.h>


int main(int argc, char** argv) {
  CLI::App app{"bathyslam-server: the bathyslam gRPC service"};
  std::string listen = "127.0.0.1:50051";
  app.add_option("--listen", listen, "address to listen on")->capture_default_str()
      ->envname("BATHYSLAM_LISTEN");
  CLI11_PARSE(app, argc, argv);

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
