#pragma once
// http (API): the service's products where GIS tools and browsers read them. GDAL reads a job's
// map as a cloud-optimised GeoTIFF over range requests (`/vsicurl/`), and anything that speaks
// HTTP gets the lists of surveys and jobs, a job's state, its report, plots, BAG and corrected
// GSF. The same tokens as the gRPC API (`Authorization: Bearer`), the same tenant isolation:
// another tenant's ids answer 404 as unknown ones do. Read only: uploads and jobs stay on gRPC.
//
// On cpp-httplib (Debian's libcpp-httplib-dev): a thread pool, TLS from the same PEM files as
// gRPC, and a few hundred lines less than Boost.Beast for the same routes. Its own range
// handling is bypassed (byte_range.h): in Debian's 0.11.4 a range beyond the end is answered
// with a negative length.
#include <memory>
#include <string>
#include <thread>

#include "server/services/service_context.h"

namespace httplib {
class Server;
}

namespace bathyslam::server::http {

struct HttpOptions {
  std::string host = "127.0.0.1";
  int port = 0;  // 0: any free port
  std::string tls_cert, tls_key, tls_client_ca;  // PEM files; no certificate: plain HTTP
};

class HttpApi {
 public:
  // Binds the port (throws std::runtime_error naming the address when it cannot) and serves on
  // a thread of its own until destroyed.
  HttpApi(ServiceContext& context, const HttpOptions& options);
  ~HttpApi();
  HttpApi(const HttpApi&) = delete;
  HttpApi& operator=(const HttpApi&) = delete;
  int port() const { return port_; }

 private:
  void add_routes();
  ServiceContext& context_;
  std::unique_ptr<httplib::Server> server_;
  int port_ = 0;
  std::thread thread_;
};

}  // namespace bathyslam::server::http
