#pragma once
// The CLI's side of the API: where the server is (--server or BATHYSLAM_SERVER), the token
// (BATHYSLAM_TOKEN, sent as `authorization: Bearer ...`), and failed calls as exceptions that
// carry the server's message.
#include <memory>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>
#include <grpcpp/grpcpp.h>

namespace bathyslam::cli {

struct Remote {
  std::string server = "127.0.0.1:50051";
  std::string token;
  bool tls = false;  // --tls: the server's certificate is checked against the system's CAs or --ca
  std::string ca;    // PEM file of the CA (or self-signed certificate) to trust instead
  std::string cert, key;  // PEM files: this client's certificate, for a server that requires one

  std::shared_ptr<grpc::Channel> channel() const;
  // A context with the token; `deadline_s` > 0 bounds the call.
  std::unique_ptr<grpc::ClientContext> context(double deadline_s = 0) const;
};

// Adds --server, --token, --tls, --ca, --cert and --key (with environment variables) to a subcommand.
void add_remote_options(CLI::App* command, Remote& remote);

class CallFailed : public std::runtime_error {
 public:
  CallFailed(const std::string& call, const grpc::Status& status);
  grpc::StatusCode code() const { return code_; }

 private:
  grpc::StatusCode code_;
};

// Throws CallFailed unless `status` is OK.
void check(const std::string& call, const grpc::Status& status);

// "12.3 MB" and a progress bar line on stderr: "\r  label [#####     ]  42.0 %  detail".
std::string megabytes(double bytes);
void progress_line(const std::string& label, double fraction, const std::string& detail);

}  // namespace bathyslam::cli
