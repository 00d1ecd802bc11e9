#pragma once
// gRPC reflection lists every method and message, and its service asks for no token: this gate
// holds its calls to the services' own rule (a valid API token, or a development server's dev
// tenant). A call without one is cancelled before the reflection service answers.
#include <memory>
#include <string>

#include <grpcpp/support/server_interceptor.h>

#include "server/services/service_context.h"

namespace bathyslam::server {

class TokenGateFactory : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  // Gates the methods whose full name starts with `prefix` (e.g. "/grpc.reflection.").
  TokenGateFactory(const ServiceContext& context, std::string prefix) : context_(context), prefix_(std::move(prefix)) {}
  grpc::experimental::Interceptor* CreateServerInterceptor(grpc::experimental::ServerRpcInfo* info) override;

 private:
  const ServiceContext& context_;
  std::string prefix_;
};

}  // namespace bathyslam::server
