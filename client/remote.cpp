#include "client/remote.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>

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

std::string read_text_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

std::shared_ptr<grpc::Channel> Remote::channel() const {
  grpc::ChannelArguments arguments;
  arguments.SetMaxReceiveMessageSize(64 << 20);  // a report with its plots
  if (!tls && !(ca.empty() && cert.empty() && key.empty())) throw std::runtime_error("--ca, --cert, --key: only with --tls");
  if (cert.empty() != key.empty()) throw std::runtime_error("--cert and --key go together");
  if (!tls) return grpc::CreateCustomChannel(server, grpc::InsecureChannelCredentials(), arguments);
  grpc::SslCredentialsOptions options;
  if (!ca.empty()) options.pem_root_certs = read_text_file(ca);
  if (!cert.empty()) {
    options.pem_cert_chain = read_text_file(cert);
    options.pem_private_key = read_text_file(key);
  }
  return grpc::CreateCustomChannel(server, grpc::SslCredentials(options), arguments);
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
  command->add_flag("--tls", remote.tls, "connect with TLS")->envname("BATHYSLAM_TLS");
  command->add_option("--ca", remote.ca, "PEM file of the CA to trust (with --tls)")->envname("BATHYSLAM_CA");
  command->add_option("--cert", remote.cert, "PEM client certificate, for mutual TLS")->envname("BATHYSLAM_CERT");
  command->add_option("--key", remote.key, "PEM private key of --cert")->envname("BATHYSLAM_KEY");
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
