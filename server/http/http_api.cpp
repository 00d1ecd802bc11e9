#include "server/http/http_api.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <stdexcept>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "core/io/crs.h"
#include "core/products/corrected_gsf.h"
#include "core/tiles/relief_colours.h"
#include "server/http/byte_range.h"
#include "server/http/web_files.h"
#include "server/log.h"

namespace bathyslam::server::http {
namespace {

namespace storage = bathyslam::storage;
using json = nlohmann::json;

constexpr std::int64_t kChunkBytes = 1 << 20;  // read from the database per write: memory per download
constexpr int kThreads = 32;                    // the library's pool
constexpr int kMaxEventStreams = 24;            // of them, at most this many held by event streams
constexpr auto kEventWait = std::chrono::seconds(2);  // between checks that an event stream's client is there

int http_status(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK: return 200;
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::OUT_OF_RANGE: return 400;
    case grpc::StatusCode::UNAUTHENTICATED: return 401;
    case grpc::StatusCode::PERMISSION_DENIED: return 403;
    case grpc::StatusCode::NOT_FOUND: return 404;
    case grpc::StatusCode::ALREADY_EXISTS:
    case grpc::StatusCode::ABORTED:
    case grpc::StatusCode::FAILED_PRECONDITION: return 409;
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return 429;
    case grpc::StatusCode::UNAVAILABLE: return 503;
    case grpc::StatusCode::DEADLINE_EXCEEDED: return 504;
    default: return 500;
  }
}

// Text from the request (a decoded path, a header) may be any bytes: they are replaced, never
// thrown about, since a throw in the library's error handler ends the process.
void send_json(httplib::Response& res, const json& body, int status = 200) {
  res.status = status;
  res.set_content(body.dump(-1, ' ', false, json::error_handler_t::replace), "application/json");
}

// A positive id given as text (a query parameter, a header), refused naming `field`.
std::int64_t id_of(const std::string& text, const std::string& field) {
  std::int64_t id = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), id);
  if (error != std::errc() || end != text.data() + text.size() || id <= 0)
    throw invalid(field, "'" + text + "' is not a positive 64-bit id");
  return id;
}

std::int64_t id_in_path(const httplib::Request& req, int group, const std::string& field) {
  return id_of(req.matches[group], field);
}

// A tile coordinate: any int (xyz_tile_bounds says which are in range).
int coordinate_in_path(const httplib::Request& req, int group, const std::string& field) {
  const std::string text = req.matches[group];
  int value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) throw invalid(field, "'" + text + "' is not a tile coordinate");
  return value;
}

// The lowest zoom whose pixels are as fine as the map's cells at `latitude`: past it, tiles only
// magnify.
int finest_zoom(double resolution_m, double latitude_deg) {
  const double equator = 2 * M_PI * 6378137.0 * std::cos(latitude_deg * M_PI / 180) / kXyzTileSide;
  return std::clamp(static_cast<int>(std::ceil(std::log2(equator / resolution_m))), 0, kXyzMaxZoom);
}

std::string hex_colour(const cv::Vec3b& bgr) {
  char text[8];
  std::snprintf(text, sizeof text, "#%02x%02x%02x", bgr[2], bgr[1], bgr[0]);
  return text;
}

int page_size_of(const httplib::Request& req) {
  if (!req.has_param("page_size")) return page_size(0);
  const std::string text = req.get_param_value("page_size");
  int size = -1;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), size);
  if (error != std::errc() || end != text.data() + text.size()) throw invalid("page_size", "'" + text + "' is not a number");
  return page_size(size);
}

// One page of a list read with one row more than `size` (trim_to_page), as {key: [...],
// "next_page_token"} where there is a next page.
template <typename Row, typename ToJson>
json page_of(std::vector<Row> rows, int size, const char* key, ToJson to_json) {
  const bool more = trim_to_page(rows, size);
  json items = json::array();
  for (const Row& row : rows) items.push_back(to_json(row));
  json reply = {{key, std::move(items)}};
  if (more) reply["next_page_token"] = std::to_string(rows.back().id);
  return reply;
}

json job_json(const storage::JobRecord& job) {
  json j = {{"id", job.id},
            {"survey_id", job.survey_id},
            {"configuration", job.configuration},
            {"state", storage::to_string(job.state)},
            {"stage", job.stage},
            {"progress", job.progress},
            {"attempts", job.attempts},
            {"created_at", job.created_at},
            {"started_at", job.started_at},
            {"finished_at", job.finished_at},
            {"more_survey_ids", job.more_survey_ids},
            {"site_id", job.site_id.value_or(0)}};
  if (job.error) j["error"] = *job.error;
  return j;
}

// A stored product read by ranges: one database read of at most a MiB per write to the client.
struct Product {
  std::int64_t size = 0;
  std::string content_type;
  std::string etag;  // etag() below: the same while the job's attempt is
  std::function<storage::Bytes(std::int64_t offset, std::int64_t length)> read;
};

void send_product(const httplib::Request& req, httplib::Response& res, const Product& product) {
  res.set_header("Accept-Ranges", "bytes");
  res.set_header("ETag", product.etag);
  if (req.get_header_value("If-None-Match") == product.etag) {
    res.status = 304;
    return;
  }
  const RangeAnswer answer = answer_range(req.get_header_value("Range"), product.size);
  if (answer.kind == RangeAnswer::kUnsatisfiable) {
    res.set_header("Content-Range", "bytes */" + std::to_string(product.size));
    send_json(res, {{"error", "Range: " + req.get_header_value("Range") + " starts beyond the " +
                                  std::to_string(product.size) + " bytes of the file"}},
              416);
    return;
  }
  if (answer.kind == RangeAnswer::kPartial) {
    res.status = 206;
    res.set_header("Content-Range", "bytes " + std::to_string(answer.offset) + "-" +
                                        std::to_string(answer.offset + answer.length - 1) + "/" +
                                        std::to_string(product.size));
  } else {
    res.status = 200;
  }
  const std::int64_t start = answer.offset;
  const auto read = product.read;
  res.set_content_provider(static_cast<std::size_t>(answer.length), product.content_type,
                           [read, start](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
                             // Runs after the handler, outside its error handling: a failure ends the
                             // response short, which the client sees as a cut download.
                             try {
                               const storage::Bytes data = read(start + static_cast<std::int64_t>(offset),
                                                                std::min<std::int64_t>(static_cast<std::int64_t>(length), kChunkBytes));
                               if (data.empty()) return false;
                               return sink.write(reinterpret_cast<const char*>(data.data()), data.size());
                             } catch (const std::exception& error) {
                               log("http: reading a product at byte %zu: %s", offset, error.what());
                               return false;
                             }
                           });
}

// A product is the same bytes while the job's attempt is: a retried job may store new ones.
std::string etag(const storage::JobRecord& job, const std::string& product, std::int64_t size) {
  return "\"job" + std::to_string(job.id) + "-" + std::to_string(job.attempts) + "-" + product + "-" + std::to_string(size) +
         "\"";
}

Product stored_map(ServiceContext& context, const storage::JobRecord& job, const std::string& format,
                   const std::string& content_type) {
  const storage::TileKey key{format, 0, 0, 0};
  const auto size = context.results.tile_size(job.id, key);
  if (!size) throw Refusal(grpc::StatusCode::NOT_FOUND, "job " + std::to_string(job.id) + " has no " + format + " map");
  return {*size, content_type, etag(job, format, *size),
          [&context, id = job.id, key](std::int64_t offset, std::int64_t length) {
            return context.results.tile_bytes(id, key, offset, length);
          }};
}

}  // namespace

HttpApi::HttpApi(ServiceContext& context, JobEventBell& bell, const HttpOptions& options)
    : context_(context), bell_(bell), request_slots_(context.limits.max_http_requests) {
  if (options.tls_cert.empty() != options.tls_key.empty()) throw std::runtime_error("--tls-cert and --tls-key go together");
  if (options.tls_cert.empty()) {
    server_ = std::make_unique<httplib::Server>();
  } else {
    auto tls = std::make_unique<httplib::SSLServer>(options.tls_cert.c_str(), options.tls_key.c_str(),
                                                    options.tls_client_ca.empty() ? nullptr : options.tls_client_ca.c_str());
    if (!tls->is_valid()) throw std::runtime_error("--http: cannot serve TLS with " + options.tls_cert + " and " + options.tls_key);
    server_ = std::move(tls);
    tls_ = true;
  }
  server_->new_task_queue = [] { return new httplib::ThreadPool(kThreads); };
  // The library's range handling is off for every request, routed or not: send_product answers
  // ranges of the products (byte_range.h), and a page, a plot or an error is sent whole.
  server_->set_pre_routing_handler([](const httplib::Request& req, httplib::Response&) {
    const_cast<httplib::Request&>(req).ranges.clear();
    return httplib::Server::HandlerResponse::Unhandled;
  });
  // Headers and body go out in two writes: with Nagle's algorithm the second waited for the
  // client's delayed ACK, 40 ms on every cached tile (p99 49 ms against p50 2 ms).
  server_->set_tcp_nodelay(true);
  server_->set_keep_alive_max_count(1000);  // a map viewer fetches hundreds of tiles a connection
  add_routes();
  add_tile_routes();
  add_event_routes();
  port_ = options.port == 0 ? server_->bind_to_any_port(options.host)
                            : (server_->bind_to_port(options.host, options.port) ? options.port : -1);
  if (port_ <= 0)
    throw std::runtime_error("--http: cannot listen on " + options.host + ":" + std::to_string(options.port));
  thread_ = std::thread([this] { server_->listen_after_bind(); });
  // stop() does nothing before the loop runs: wait for it, so that destroying this right away
  // cannot leave the thread listening.
  for (int waited = 0; waited < 5000 && !server_->is_running(); ++waited) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

HttpApi::~HttpApi() {
  server_->stop();
  if (thread_.joinable()) thread_.join();
}

void HttpApi::route(const std::string& pattern, Body body) {
  // Every route: the caller's tenant first, then one of its request slots, refusals as JSON
  // {"error": ...} with the status the gRPC API would give in HTTP's words, and one log line with
  // what was sent.
  server_->Get(pattern, [this, body](const httplib::Request& req, httplib::Response& res) {
    res.status = 200;
    const grpc::Status status = status_of(("HTTP GET " + req.path).c_str(), [&] {
      const std::string authorization = req.get_header_value("Authorization");
      const std::int64_t tenant =
          tenant_of_authorization(context_, req.has_header("Authorization") ? &authorization : nullptr);
      auto slot = std::make_shared<StreamSlots::Slot>(
          slot_or_refuse(request_slots_, tenant, "HTTP requests in progress on this server", "--max-http-requests",
                         "wait for one to finish"));
      body(req, res, tenant);
      // A download's or an event stream's bytes go out after this returns, on the same thread:
      // the slot goes with them (the provider's copies end with the response).
      if (res.content_provider_) {
        res.content_provider_ = [send = std::move(res.content_provider_), slot](std::size_t offset, std::size_t length,
                                                                                  httplib::DataSink& sink) {
          return send(offset, length, sink);
        };
      }
    });
    if (!status.ok()) {
      if (status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) res.set_header("Retry-After", "1");
      if (status.error_code() == grpc::StatusCode::UNAUTHENTICATED) res.set_header("WWW-Authenticate", "Bearer");
      res.content_provider_ = nullptr;
      send_json(res, {{"error", status.error_message()}}, http_status(status.error_code()));
    }
    log("http %s %s %d %zu bytes", req.method.c_str(), req.path.c_str(), res.status,
        res.content_provider_ ? res.content_length_ : res.body.size());
  });
}

void HttpApi::add_routes() {
  route("/v1/surveys", [this](const httplib::Request& req, httplib::Response& res, std::int64_t tenant) {
    const int size = page_size_of(req);
    send_json(res, page_of(context_.surveys.list_surveys(tenant, page_token(req.get_param_value("page_token")), size + 1),
                           size, "surveys", [](const storage::SurveyRecord& s) {
                             return json{{"id", s.id}, {"name", s.name}, {"crs", s.crs}, {"ready", s.ready}};
                           }));
  });
  route("/v1/jobs", [this](const httplib::Request& req, httplib::Response& res, std::int64_t tenant) {
    const int size = page_size_of(req);
    std::optional<std::int64_t> survey;
    if (req.has_param("survey_id")) survey = owned_survey(context_, tenant, id_of(req.get_param_value("survey_id"), "survey_id")).id;
    std::optional<std::int64_t> site;
    if (req.has_param("site_id")) site = owned_site(context_, tenant, id_of(req.get_param_value("site_id"), "site_id")).id;
    send_json(res, page_of(context_.jobs.list_jobs(tenant, survey, page_token(req.get_param_value("page_token")), size + 1, site),
                           size, "jobs", job_json));
  });
  route(R"(/v1/jobs/([0-9]+))", [this](const httplib::Request& req, httplib::Response& res, std::int64_t tenant) {
    send_json(res, job_json(owned_job(context_, tenant, id_in_path(req, 1, "job_id"))));
  });
  route(R"(/v1/jobs/([0-9]+)/report\.json)", [this](const httplib::Request& req, httplib::Response& res, std::int64_t tenant) {
    const storage::JobRecord job = job_with_results(context_, tenant, id_in_path(req, 1, "job_id"));
    auto report = context_.results.load_report(job.id);
    if (!report) throw Refusal(grpc::StatusCode::NOT_FOUND, "job " + std::to_string(job.id) + " is " + storage::to_string(job.state) + " and has no report");
    send_json(res, report->report);
  });
  route(R"(/v1/jobs/([0-9]+)/plots/([A-Za-z0-9_-]+\.png))",
        [this](const httplib::Request& req, httplib::Response& res, std::int64_t tenant) {
          const storage::JobRecord job = job_with_results(context_, tenant, id_in_path(req, 1, "job_id"));
          const std::string name = req.matches[2];
          const auto report = context_.results.load_report(job.id);
          if (!report || !report->plots.contains(name))
            throw Refusal(grpc::StatusCode::NOT_FOUND, "job " + std::to_string(job.id) + " has no plot '" + name + "'");
          const storage::Bytes& png = report->plots.at(name);
          res.set_content(std::string(png.begin(), png.end()), "image/png");
        });
  route(R"(/v1/jobs/([0-9]+)/trajectory\.geojson)",
        [this](const httplib::Request& req, httplib::Response& res, std::int64_t tenant) {
          const storage::JobRecord job = job_with_results(context_, tenant, id_in_path(req, 1, "job_id"));
          send_json(res, trajectory_geojson(job));
        });
  route(R"(/v1/jobs/([0-9]+)/map\.tif)", [this](const httplib::Request& req, httplib::Response& res, std::int64_t tenant) {
    const storage::JobRecord job = job_with_results(context_, tenant, id_in_path(req, 1, "job_id"));
    send_product(req, res, stored_map(context_, job, "cog", "image/tiff; application=geotiff; profile=cloud-optimized"));
  });
  route(R"(/v1/jobs/([0-9]+)/map\.bag)", [this](const httplib::Request& req, httplib::Response& res, std::int64_t tenant) {
    const storage::JobRecord job = job_with_results(context_, tenant, id_in_path(req, 1, "job_id"));
    send_product(req, res, stored_map(context_, job, "bag", "application/x-hdf5"));
  });
  // The job files: corrected.gsf (in a job of several surveys corrected.K.gsf for the K-th:
  // map_service's GSF) and difference_J_K.tif (the change from survey J to K: its DIFFERENCE).
  route(R"(/v1/jobs/([0-9]+)/(corrected(\.[0-9]+)?\.gsf|difference_[0-9]+_[0-9]+\.tif))",
        [this](const httplib::Request& req, httplib::Response& res, std::int64_t tenant) {
          const storage::JobRecord job = job_with_results(context_, tenant, id_in_path(req, 1, "job_id"));
          const std::string name = req.matches[2];
          const auto size = context_.results.file_size(job.id, name);
          if (!size) throw Refusal(grpc::StatusCode::NOT_FOUND, "job " + std::to_string(job.id) + " has no " + name);
          const char* type = name.ends_with(".gsf") ? "application/octet-stream"
                                                    : "image/tiff; application=geotiff; profile=cloud-optimized";
          send_product(req, res,
                       {*size, type, etag(job, name, *size), [this, id = job.id, name](std::int64_t offset, std::int64_t length) {
                          return context_.results.file_bytes(id, name, offset, length);
                        }});
        });
  // The page and its files (web_files.h): public, as any page is; what it shows asks for the token.
  const auto serve_file = [](const std::string& name, httplib::Response& res) {
    const auto file = web_files().find(name);
    if (file == web_files().end()) {
      res.status = 404;  // the error handler says so
      return;
    }
    res.status = 200;
    res.set_header("Cache-Control", "no-cache");  // a new server build brings a new page
    res.set_content(std::string(file->second.bytes), std::string(file->second.content_type));
  };
  server_->Get("/", [serve_file](const httplib::Request&, httplib::Response& res) { serve_file("/index.html", res); });
  server_->Get(R"(/static/([A-Za-z0-9_./-]+))", [serve_file](const httplib::Request& req, httplib::Response& res) {
    serve_file("/" + std::string(req.matches[1]), res);  // a name not in the map (.., //) is 404
  });
  // Any other path, and the library's own refusals (a malformed Range: 416), say so in JSON too.
  server_->set_error_handler([](const httplib::Request& req, httplib::Response& res) {
    if (!res.body.empty() || res.content_provider_) return;
    // Nothing may leave this handler: the library calls it outside its own try.
    std::string what = "refused (HTTP " + std::to_string(res.status) + ")";
    if (res.status == 404) what = "no such resource: " + req.path;
    if (res.status == 416) what = "Range: cannot read '" + req.get_header_value("Range") + "'";
    if (res.status == 400) what = "the request line or a header is malformed or too long (8 KiB at most)";
    if (res.status == 414) what = "the URI is too long (8 KiB at most)";
    send_json(res, {{"error", what}}, res.status);
  });
}

namespace {

// The job, if the tenant's and succeeded: the tiles are drawn from its final map and cached as
// such (a running or retried job's map may still change).
storage::JobRecord finished_map_job(ServiceContext& context, std::int64_t tenant, std::int64_t job_id) {
  storage::JobRecord job = job_with_results(context, tenant, job_id);
  if (job.state != storage::JobState::kSucceeded)
    throw Refusal(grpc::StatusCode::FAILED_PRECONDITION,
                  "job_id: job " + std::to_string(job.id) + " is " + storage::to_string(job.state) + "; its tiles come when it succeeds");
  return job;
}

}  // namespace

std::shared_ptr<const XyzTileSource> HttpApi::tile_source(const storage::JobRecord& job) {
  return tiles_.source(job.id, [&] {
    const auto grid = context_.results.map_grid(job.id);
    auto cog = context_.results.tile(job.id, {"cog", 0, 0, 0});
    if (!grid || grid->epsg <= 0 || !cog)
      throw Refusal(grpc::StatusCode::NOT_FOUND, "job " + std::to_string(job.id) + " has no map");
    return std::make_shared<const XyzTileSource>(std::move(*cog), "EPSG:" + std::to_string(grid->epsg));
  });
}

void HttpApi::add_tile_routes() {
  route(R"(/v1/jobs/([0-9]+)/tiles\.json)", [this](const httplib::Request& req, httplib::Response& res, std::int64_t tenant) {
    const storage::JobRecord job = finished_map_job(context_, tenant, id_in_path(req, 1, "job_id"));
    const std::shared_ptr<const XyzTileSource> source = tile_source(job);
    const auto [west, south, east, north] = source->lon_lat_bounds();
    const int finest = finest_zoom(source->resolution(), (south + north) / 2);
    const std::string base = (tls_ ? "https://" : "http://") + req.get_header_value("Host");
    const auto [lo, hi] = source->ramp_range();
    json ramp = json::array();
    for (const cv::Vec3b& colour : turbo_ramp()) ramp.push_back(hex_colour(colour));
    send_json(res, {{"tilejson", "3.0.0"},
                    {"name", "job " + std::to_string(job.id)},
                    {"scheme", "xyz"},
                    {"tiles", {base + "/v1/jobs/" + std::to_string(job.id) + "/tiles/{z}/{x}/{y}.png"}},
                    {"minzoom", 0},
                    {"maxzoom", std::min(kXyzMaxZoom, finest + 2)},
                    {"bounds", {west, south, east, north}},
                    {"center", {(west + east) / 2, (south + north) / 2, std::max(0, finest - 3)}},
                    // How to read a tile's colours back (with ?shade=0): ramp[k] is the elevation
                    // lo + (hi - lo) k / 255, clamped at both ends.
                    {"bathyslam", {{"elevation_range_m", {lo, hi}}, {"ramp", ramp}, {"unshaded_query", "shade=0"}}}});
  });
  route(R"(/v1/jobs/([0-9]+)/tiles/(-?[0-9]+)/(-?[0-9]+)/(-?[0-9]+)\.png)",
        [this](const httplib::Request& req, httplib::Response& res, std::int64_t tenant) {
          const storage::JobRecord job = finished_map_job(context_, tenant, id_in_path(req, 1, "job_id"));
          const int z = coordinate_in_path(req, 2, "z"), x = coordinate_in_path(req, 3, "x"), y = coordinate_in_path(req, 4, "y");
          try {
            xyz_tile_bounds(z, x, y);
          } catch (const std::invalid_argument& error) {
            throw invalid("tile " + std::to_string(z) + "/" + std::to_string(x) + "/" + std::to_string(y), error.what());
          }
          const bool shade = req.get_param_value("shade") != "0";
          const std::shared_ptr<const std::string> png =
              tiles_.tile(job.id, z, x, y, shade, [&] { return tile_source(job); });
          if (!png)
            throw Refusal(grpc::StatusCode::NOT_FOUND, "tile " + std::to_string(z) + "/" + std::to_string(x) + "/" +
                                                           std::to_string(y) + " is outside job " + std::to_string(job.id) + "'s map");
          res.set_header("Cache-Control", "private, max-age=86400");  // a job's map never changes
          res.set_content(*png, "image/png");
        });
}

namespace {

std::string server_sent_event(const std::string& name, const json& data, std::int64_t id = 0) {
  return (id > 0 ? "id: " + std::to_string(id) + "\n" : std::string()) + "event: " + name + "\ndata: " + data.dump() + "\n\n";
}

}  // namespace

void HttpApi::add_event_routes() {
  // A job's progress as server-sent events (what a browser's EventSource reads): each stored
  // event as "progress" with its id (Last-Event-ID resumes after it), then one "end" with the
  // job as /v1/jobs/{id} shows it. The bell wakes the stream, as it wakes WatchJob.
  route(R"(/v1/jobs/([0-9]+)/events)", [this](const httplib::Request& req, httplib::Response& res, std::int64_t tenant) {
    const storage::JobRecord job = owned_job(context_, tenant, id_in_path(req, 1, "job_id"));
    std::int64_t last = 0;
    if (req.has_header("Last-Event-ID")) last = id_of(req.get_header_value("Last-Event-ID"), "Last-Event-ID");
    auto slot = std::make_shared<StreamSlots::Slot>(
        slot_or_refuse(event_slots_, tenant, "event streams open on this server", "8 a tenant", "close one first"));
    if (++event_streams_ > kMaxEventStreams) {
      --event_streams_;
      throw Refusal(grpc::StatusCode::UNAVAILABLE, "this server has " + std::to_string(kMaxEventStreams) +
                                                       " event streams open, its limit; watch the job with gRPC's "
                                                       "WatchJob or poll GET /v1/jobs/" + std::to_string(job.id));
    }
    std::shared_ptr<void> open(nullptr, [this](void*) { --event_streams_; });
    res.set_header("Cache-Control", "no-cache");
    res.set_chunked_content_provider(
        "text/event-stream", [this, id = job.id, last, slot, open](std::size_t, httplib::DataSink& sink) mutable {
          const auto send = [&](const std::string& text) { return sink.write(text.data(), text.size()); };
          try {
            const std::uint64_t rings = bell_.rings(id);
            const auto now = context_.jobs.job(id);
            if (!now) {
              sink.done();
              return true;
            }
            for (const storage::StoredJobEvent& stored : context_.jobs.events_after(id, last)) {
              if (!send(server_sent_event("progress",
                                          {{"stage", stored.event.stage}, {"progress", stored.event.progress},
                                           {"message", stored.event.message}, {"attempt", stored.event.attempt},
                                           {"at", stored.at}},
                                          stored.id)))
                return false;
              last = stored.id;
            }
            if (storage::finished(now->state)) {
              send(server_sent_event("end", job_json(*now)));
              sink.done();
              return true;
            }
            // Nothing new: a comment line, which is how a client that went away is noticed.
            if (!bell_.wait(id, rings, kEventWait)) return send(": waiting\n\n");
            return true;
          } catch (const std::exception& error) {
            log("http: event stream of job %lld: %s", static_cast<long long>(id), error.what());
            return false;
          }
        });
  });
}

json HttpApi::trajectory_geojson(const storage::JobRecord& job) {
  const std::vector<storage::SubmapPose> submaps = context_.results.submap_poses(job.id);
  const std::vector<Eigen::Isometry3d> corrected = context_.results.load_optimized_poses(job.id);
  const auto grid = context_.results.map_grid(job.id);
  const auto origin = context_.results.origin(job.id);
  if (submaps.empty() || corrected.size() != submaps.size() || !grid || grid->epsg <= 0 || !origin)
    throw Refusal(grpc::StatusCode::NOT_FOUND, "job " + std::to_string(job.id) + " is " + storage::to_string(job.state) +
                                                   " and has no trajectory");
  const GeographicProjection projection("EPSG:" + std::to_string(grid->epsg));
  const auto lon_lat = [&](const Eigen::Isometry3d& pose) {
    const auto p = projection.inverse(pose.translation().x() + origin->easting, pose.translation().y() + origin->northing);
    return json::array({p.longitude_deg, p.latitude_deg});
  };
  const auto line = [](const std::string& kind, json coordinates, json properties = json::object()) {
    properties["kind"] = kind;
    return json{{"type", "Feature"},
                {"properties", properties},
                {"geometry", {{"type", "LineString"}, {"coordinates", std::move(coordinates)}}}};
  };
  json dead_reckoning = json::array(), solved = json::array(), features = json::array();
  for (std::size_t i = 0; i < submaps.size(); ++i) {
    dead_reckoning.push_back(lon_lat(submaps[i].dr_pose));
    solved.push_back(lon_lat(corrected[i]));
  }
  features.push_back(line("dead_reckoning", std::move(dead_reckoning)));
  features.push_back(line("corrected", std::move(solved)));
  // The loop closures the published map was made with, between the submaps' corrected poses.
  for (const Constraint& c : context_.results.load_constraints(job.id)) {
    if (c.type != ConstraintType::kLoop || !c.in_graph()) continue;
    if (c.from < 0 || c.to < 0 || static_cast<std::size_t>(std::max(c.from, c.to)) >= corrected.size()) continue;
    features.push_back(line("loop_closure", json::array({lon_lat(corrected[c.from]), lon_lat(corrected[c.to])}),
                            {{"from", c.from}, {"to", c.to}}));
  }
  return {{"type", "FeatureCollection"}, {"features", std::move(features)}};
}

}  // namespace bathyslam::server::http
