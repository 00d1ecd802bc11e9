#include "client/remote.h"

#include <algorithm>
#include <cstdio>

namespace bathyslam::cli {
namespace {

const char* code_name(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::INVALID_ARGUMENT: return "INVALID_ARGUMENT";
    case grpc::StatusCode::NOT_FOUND: return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS: return "ALREADY_EXISTS";
    case grpc::StatusCode::FAILED_PRECONDITION: return "FAILED_PRECONDITION";
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::ABORTED: return "ABORTED";
    case grpc::StatusCode::UNAVAILABLE: return "UNAVAILABLE";
    case grpc::StatusCode::UNAUTHENTICATED: return "UNAUTHENTICATED";
    case grpc::StatusCode::DEADLINE_EXCEEDED: return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::CANCELLED: return "CANCELLED";
    default: return "error";
  }
}

}  // namespace

std::shared_ptr<grpc::Channel> Remote::channel() const {
  grpc::ChannelArguments arguments;
  arguments.SetMaxReceiveMessageSize(64 << 20);  // a report with its plots
  return grpc::CreateCustomChannel(server, grpc::InsecureChannelCredentials(), arguments);
}

std::unique_ptr<grpc::ClientContext> Remote::context(double deadline_s) const {
  auto context = std::make_unique<grpc::ClientContext>();
  if (!token.empty()) context->AddMetadata("authorization", "Bearer " + token);
  if (deadline_s > 0)
    context->set_deadline(std::chrono::system_clock::now() +
                          std::chrono::milliseconds(static_cast<long long>(deadline_s * 1000)));
  return context;
}

void add_remote_options(CLI::App* command, Remote& remote) {
  command->add_option("--server", remote.server, "server address host:port")->envname("BATHYSLAM_SERVER")
      ->capture_default_str();
  command->add_option("--token", remote.token, "API token (bathyslam-server token)")->envname("BATHYSLAM_TOKEN");
}

CallFailed::CallFailed(const std::string& call, const grpc::Status& status)
    : std::runtime_error(call + ": " + code_name(status.error_code()) + ": " + status.error_message()),
      code_(status.error_code()) {}

void check(const std::string& call, const grpc::Status& status) {
  if (!status.ok()) throw CallFailed(call, status);
}

std::string megabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f MB", bytes / 1e6);
  return text;
}

void progress_line(const std::string& label, double fraction, const std::string& detail) {
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * kWidth + 0.5);
  std::fprintf(stderr, "\r  %-18s [%s%s] %5.1f %%  %s   ", label.c_str(), std::string(filled, '#').c_str(),
               std::string(kWidth - filled, ' ').c_str(), 100 * std::clamp(fraction, 0.0, 1.0), detail.c_str());
  std::fflush(stderr);
}

}  // namespace bathyslam::cli
