#pragma once
// http (API): the service's products where GIS tools and browsers read them. GDAL reads a job's
// map as a cloud-optimised GeoTIFF over range requests (`/vsicurl/`), and anything that speaks
// HTTP gets the lists of surveys and jobs, a job's state, its report, plots, BAG and corrected
// GSF. The same tokens as the gRPC API (`Authorization: Bearer`), the same tenant isolation:
// another tenant's ids answer 404 as unknown ones do. Read only: uploads and jobs stay on gRPC.
//
// On cpp-httplib (Debian's libcpp-httplib-dev): a thread pool, TLS from the same PEM files as
// gRPC, and a few hundred lines less than Boost.Beast for the same routes. The map is also
// served as XYZ tiles in Web Mercator (core/tiles/xyz_tiles.h) with a TileJSON document, for
// web maps and QGIS. The library's range handling is switched off for every request (a
// pre-routing handler; byte_range.h answers ranges of the products): in Debian's 0.11.4 a range
// beyond the end is answered with a negative length. A Range header its parser refuses is
// still its own 416, before any handler runs.
#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "server/http/xyz_cache.h"
#include "server/services/job_event_bell.h"
#include "server/services/service_context.h"
#include "server/services/stream_slots.h"

namespace httplib {
class Server;
struct Request;
struct Response;
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
  // `bell` wakes the job event streams (GET /v1/jobs/{id}/events) as it wakes WatchJob.
  HttpApi(ServiceContext& context, JobEventBell& bell, const HttpOptions& options);
  ~HttpApi();
  HttpApi(const HttpApi&) = delete;
  HttpApi& operator=(const HttpApi&) = delete;
  int port() const { return port_; }

 private:
  using Body = std::function<void(const httplib::Request&, httplib::Response&, std::int64_t tenant)>;
  // A GET route whose body runs as the caller's tenant (route in http_api.cpp).
  void route(const std::string& pattern, Body body);
  void add_routes();
  void add_tile_routes();
  void add_event_routes();
  std::shared_ptr<const XyzTileSource> tile_source(const storage::JobRecord& job);
  // The dead-reckoning and corrected submap tracks and the accepted loop closures, in WGS 84.
  nlohmann::json trajectory_geojson(const storage::JobRecord& job);
  ServiceContext& context_;
  JobEventBell& bell_;
  bool tls_ = false;
  // Each open event stream holds one of the library's threads: a tenant may hold 8, and all of
  // them together 24 of the 32 (kThreads in http_api.cpp). Idle keep-alive connections hold
  // threads too (up to 5 s each), so this bounds what streams take; it does not reserve the rest.
  StreamSlots event_slots_{8};
  std::atomic<int> event_streams_{0};
  // Every request of a tenant holds one of its slots (--max-http-requests) while it runs, a
  // download or an event stream until its last byte is sent: one tenant's slow downloads, streams
  // or a viewer's many tiles cannot take every thread from the others.
  StreamSlots request_slots_;
  XyzCache tiles_{256u << 20, 64u << 20};  // maps in memory, drawn tiles
  std::unique_ptr<httplib::Server> server_;
  int port_ = 0;
  std::thread thread_;
};

}  // namespace bathyslam::server::http
