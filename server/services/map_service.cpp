#include "server/services/map_service.h"

#include <algorithm>
#include <charconv>
#include <map>
#include <tuple>

#include "core/io/crs.h"
#include "core/products/corrected_gsf.h"
#include "core/products/difference_products.h"

namespace bathyslam::server {
namespace {

namespace storage = bathyslam::storage;

constexpr std::size_t kChunkBytes = 1 << 20;

// The API's tile formats and the names the tiles table stores them under.
std::string stored_format(v1::TileFormat format) {
  switch (format) {
    case v1::GEOTIFF: return "geotiff";
    case v1::VDB: return "openvdb";
    case v1::PNG: return "png";
    default: throw invalid("format", "GEOTIFF, VDB or PNG");
  }
}

// The whole map's formats and the names the tiles table stores them under ("" for the corrected
// GSF and the differences, which job_files holds); unspecified is the COG, as the API says. A value the API does not
// define is refused, as GetTile refuses one, rather than answered with some map.
std::string stored_map_format(v1::MapFormat format) {
  switch (format) {
    case v1::MAP_FORMAT_UNSPECIFIED:
    case v1::COG: return "cog";
    case v1::BAG: return "bag";
    case v1::GSF:
    case v1::DIFFERENCE: return "";
    default: throw invalid("format", "COG, BAG, GSF or DIFFERENCE, not " + std::to_string(static_cast<int>(format)));
  }
}

std::optional<v1::TileFormat> api_format(const std::string& stored) {
  if (stored == "geotiff") return v1::GEOTIFF;
  if (stored == "openvdb") return v1::VDB;
  if (stored == "png") return v1::PNG;
  return std::nullopt;  // the whole map (cog) is not a tile
}

void stream(grpc::ServerContext* call, const storage::Bytes& data, grpc::ServerWriter<v1::DataChunk>* writer) {
  for (std::size_t offset = 0; offset == 0 || offset < data.size(); offset += kChunkBytes) {
    if (call->IsCancelled()) return;
    v1::DataChunk chunk;
    chunk.set_offset(static_cast<std::int64_t>(offset));
    chunk.set_total_bytes(static_cast<std::int64_t>(data.size()));
    const std::size_t size = std::min(kChunkBytes, data.size() - offset);
    chunk.set_data(data.data() + offset, size);
    if (!writer->Write(chunk)) return;
    if (data.empty()) return;
  }
}

// A file stored in chunks, sent as it is read: memory is one chunk whatever the file's size.
void stream_file(grpc::ServerContext* call, ServiceContext& context, std::int64_t job_id, const std::string& name,
                 std::int64_t size, grpc::ServerWriter<v1::DataChunk>* writer) {
  std::int64_t offset = 0;
  bool open = true;
  context.results.read_file(job_id, name, [&](const storage::Bytes& data) {
    if (!open || call->IsCancelled()) return;
    v1::DataChunk chunk;
    chunk.set_offset(offset);
    chunk.set_total_bytes(size);
    chunk.set_data(data.data(), data.size());
    open = writer->Write(chunk);
    offset += static_cast<std::int64_t>(data.size());
  });
}

void set_pose(const Eigen::Isometry3d& pose, v1::Pose* out) {
  const Eigen::Quaterniond q(pose.rotation());
  out->set_easting(pose.translation().x());
  out->set_northing(pose.translation().y());
  out->set_up(pose.translation().z());
  out->set_qw(q.w());
  out->set_qx(q.x());
  out->set_qy(q.y());
  out->set_qz(q.z());
}

}  // namespace

grpc::Status MapService::GetMapInfo(grpc::ServerContext* call, const v1::GetMapInfoRequest* request, v1::MapInfo* reply) {
  return handle("GetMapInfo", call, [&] {
    const std::int64_t tenant = caller_tenant(context_, *call);
    const storage::JobRecord job = job_with_results(context_, tenant, request->job_id());
    const storage::SurveyRecord survey = owned_survey(context_, tenant, job.survey_id);
    reply->set_job_id(job.id);
    reply->set_has_gsf(context_.results.file_size(job.id, kCorrectedGsfFile).has_value());
    // The survey's CRS is checked at creation or finalization to be "EPSG:<code>".
    std::string crs = survey.crs;
    if (crs.empty())
      if (auto validation = context_.surveys.validation(survey.id); validation && validation->summary.is_object())
        crs = validation->summary.value("crs", "");
    int epsg = 0;
    if (crs.rfind("EPSG:", 0) == 0) std::from_chars(crs.data() + 5, crs.data() + crs.size(), epsg);
    reply->set_epsg(epsg);
    reply->set_crs_wkt(crs.empty() ? "" : crs_wkt(crs));
    if (auto grid = context_.results.map_grid(job.id)) {
      reply->set_epsg(grid->epsg);
      reply->set_resolution_m(grid->resolution_m);
      reply->set_min_easting(grid->min_easting);
      reply->set_min_northing(grid->min_northing);
      reply->set_max_easting(grid->max_easting);
      reply->set_max_northing(grid->max_northing);
      reply->set_tile_size_cells(grid->tile_size_cells);
      reply->set_levels(grid->levels);
    }
    std::map<std::tuple<int, int, int>, v1::TileRef> tiles;
    for (const storage::TileKey& key : context_.results.tiles(job.id)) {
      if (key.format == "cog" || key.format == "bag") {  // the whole map, not a tile
        if (key.format == "cog") reply->set_has_map(true);
        else reply->set_has_bag(true);
        continue;
      }
      v1::TileRef& ref = tiles[{key.level, key.row, key.col}];
      ref.set_level(key.level);
      ref.set_col(key.col);
      ref.set_row(key.row);
      if (auto format = api_format(key.format)) ref.add_formats(*format);
    }
    for (auto& [key, ref] : tiles) *reply->add_tiles() = std::move(ref);
  });
}

grpc::Status MapService::GetTile(grpc::ServerContext* call, const v1::GetTileRequest* request,
                                 grpc::ServerWriter<v1::DataChunk>* writer) {
  return handle("GetTile", call, [&] {
    const storage::JobRecord job = job_with_results(context_, caller_tenant(context_, *call), request->job_id());
    const std::string format = stored_format(request->format());
    if (request->level() < 0) throw invalid("level", "must not be negative");
    auto data = context_.results.tile(job.id, {format, request->level(), request->col(), request->row()});
    if (!data)
      throw Refusal(grpc::StatusCode::NOT_FOUND, "job " + std::to_string(job.id) + " has no " + format + " tile at level " +
                                                     std::to_string(request->level()) + ", col " +
                                                     std::to_string(request->col()) + ", row " + std::to_string(request->row()));
    stream(call, *data, writer);
  });
}

grpc::Status MapService::GetMap(grpc::ServerContext* call, const v1::GetMapRequest* request,
                                grpc::ServerWriter<v1::DataChunk>* writer) {
  return handle("GetMap", call, [&] {
    const storage::JobRecord job = job_with_results(context_, caller_tenant(context_, *call), request->job_id());
    const std::string format = stored_map_format(request->format());
    if (request->format() == v1::DIFFERENCE) {
      const int last = 1 + static_cast<int>(job.more_survey_ids.size());
      if (last == 1) throw invalid("format", "job " + std::to_string(job.id) + " has one survey: nothing to difference");
      const int before = request->from_epoch() == 0 ? 1 : request->from_epoch();
      if (before < 1 || before >= last)
        throw invalid("from_epoch", std::to_string(request->from_epoch()) + " is not an earlier survey of job " +
                                        std::to_string(job.id) + " (1 to " + std::to_string(last - 1) + ")");
      if (request->epoch() <= before || request->epoch() > last)
        throw invalid("epoch", std::to_string(request->epoch()) + " is not a later survey of job " + std::to_string(job.id) +
                                   " (" + std::to_string(before + 1) + " to " + std::to_string(last) + ")");
      const std::string name = "difference_" + std::to_string(before) + "_" + std::to_string(request->epoch()) + ".tif";
      const auto size = context_.results.file_size(job.id, name);
      const auto pairs = difference_pairs(last);
      const bool made = std::find(pairs.begin(), pairs.end(), std::pair{before - 1, request->epoch() - 1}) != pairs.end();
      if (!size)
        throw Refusal(grpc::StatusCode::NOT_FOUND,
                      "job " + std::to_string(job.id) + " has no " + name +
                          (made ? " (the surveys share no cell of the map: see the report)"
                                : " (a job of more than " + std::to_string(kAllDifferencesUpTo) +
                                      " surveys has each survey's difference from the first and from the one before)"));
      stream_file(call, context_, job.id, name, *size, writer);
      return;
    }
    if (format.empty()) {
      // A job of several surveys has one corrected GSF per survey: survey 1 (or 0) the first's.
      const int last = 1 + static_cast<int>(job.more_survey_ids.size());
      if (request->survey() < 0 || request->survey() > last)
        throw invalid("survey", std::to_string(request->survey()) + " is not a survey of job " + std::to_string(job.id) +
                                    " (1 to " + std::to_string(last) + ")");
      const std::string name = corrected_gsf_name(request->survey());
      const auto size = context_.results.file_size(job.id, name);
      if (!size) throw Refusal(grpc::StatusCode::NOT_FOUND, "job " + std::to_string(job.id) + " has no " + name);
      stream_file(call, context_, job.id, name, *size, writer);
      return;
    }
    auto data = context_.results.tile(job.id, {format, 0, 0, 0});
    if (!data) throw Refusal(grpc::StatusCode::NOT_FOUND, "job " + std::to_string(job.id) + " has no " + format + " map");
    stream(call, *data, writer);
  });
}

grpc::Status MapService::GetTrajectory(grpc::ServerContext* call, const v1::GetTrajectoryRequest* request,
                                       v1::Trajectory* reply) {
  return handle("GetTrajectory", call, [&] {
    const storage::JobRecord job = job_with_results(context_, caller_tenant(context_, *call), request->job_id());
    const std::vector<Eigen::Isometry3d> optimized = context_.results.load_optimized_poses(job.id);
    const std::vector<storage::SubmapPose> submaps = context_.results.submap_poses(job.id);
    if (optimized.empty() || optimized.size() != submaps.size())
      throw Refusal(grpc::StatusCode::FAILED_PRECONDITION,
                    "job_id: job " + std::to_string(job.id) + " is " + storage::to_string(job.state) + " and has no trajectory");
    reply->set_job_id(job.id);
    if (auto origin = context_.results.origin(job.id)) {
      reply->set_origin_easting(origin->easting);
      reply->set_origin_northing(origin->northing);
    }
    for (std::size_t i = 0; i < submaps.size(); ++i) {
      v1::TrajectoryPose* pose = reply->add_poses();
      pose->set_submap(submaps[i].index);
      pose->set_time(submaps[i].time_mid);
      set_pose(optimized[i], pose->mutable_optimized());
      set_pose(submaps[i].dr_pose, pose->mutable_dead_reckoning());
    }
  });
}

}  // namespace bathyslam::server
