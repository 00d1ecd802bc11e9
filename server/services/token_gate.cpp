#include "server/services/token_gate.h"

#include <string_view>

#include "server/log.h"

namespace bathyslam::server {
namespace {

using grpc::experimental::InterceptionHookPoints;

class TokenGate : public grpc::experimental::Interceptor {
 public:
  TokenGate(const ServiceContext& context, grpc::experimental::ServerRpcInfo* info) : context_(context), info_(info) {}

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(InterceptionHookPoints::POST_RECV_INITIAL_METADATA)) {
      try {
        caller_tenant(context_, *info_->server_context());
      } catch (const std::exception& refused) {  // a Refusal, or a database that cannot say
        log("%s refused: %s", info_->method(), refused.what());
        info_->server_context()->TryCancel();
      }
    }
    methods->Proceed();
  }

 private:
  const ServiceContext& context_;
  grpc::experimental::ServerRpcInfo* info_;
};

}  // namespace

grpc::experimental::Interceptor* TokenGateFactory::CreateServerInterceptor(grpc::experimental::ServerRpcInfo* info) {
  if (!std::string_view(info->method()).starts_with(prefix_)) return nullptr;
  return new TokenGate(context_, info);
}

}  // namespace bathyslam::server
