// bathyslam tiles / map: download a job's map tiles (all, or those meeting a bounding box) and
// the whole map as one Cloud Optimized GeoTIFF or BAG, and the survey's pings with the corrected
// navigation as GSF.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "bathyslam/v1/map.grpc.pb.h"
#include "client/commands.h"
#include "client/remote.h"

namespace bathyslam::cli {
namespace {

struct MapOptions {
  Remote remote;
  std::int64_t job = 0;
  std::string out;
  std::string format = "geotiff";
  std::string map_format = "cog";  // `map`: cog, bag, gsf or difference
  int epoch = 0;  // `map --format difference`: the later survey (0: 2); gsf: whose (0: the first's)
  std::vector<int> epochs;  // `map --format difference --epochs A,B`: from survey A to B
  std::vector<double> bbox;  // min easting, min northing, max easting, max northing
};

// Streams a download into `path`; returns its size.
template <typename Reader>
std::int64_t save(Reader& reader, const std::string& call, const std::filesystem::path& path) {
  // "x.tif" has no folder to make (and create_directories("") throws): it goes where we are.
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  const std::filesystem::path partial = path.string() + ".partial";
  std::ofstream out(partial, std::ios::binary);
  v1::DataChunk chunk;
  std::int64_t size = 0, total = 0;
  while (reader->Read(&chunk)) {
    out.write(chunk.data().data(), static_cast<std::streamsize>(chunk.data().size()));
    size += static_cast<std::int64_t>(chunk.data().size());
    total = chunk.total_bytes();
  }
  out.close();
  const grpc::Status status = reader->Finish();
  if (!status.ok()) std::filesystem::remove(partial);
  check(call, status);
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
  // A stream that ended early with an OK status must not pass for the whole file.
  if (size != total) {
    std::filesystem::remove(partial);
    throw std::runtime_error(path.string() + ": received " + std::to_string(size) + " of " + std::to_string(total) + " bytes");
  }
  std::filesystem::rename(partial, path);
  return size;
}

v1::TileFormat parse_format(const std::string& name) {
  if (name == "geotiff") return v1::GEOTIFF;
  if (name == "vdb") return v1::VDB;
  if (name == "png") return v1::PNG;
  throw std::invalid_argument("--format: geotiff, vdb or png");
}

const char* extension(v1::TileFormat format) {
  return format == v1::GEOTIFF ? ".tif" : format == v1::VDB ? ".vdb" : ".png";
}

// Whether a tile meets the box. Tile (level, col, row) is the square of side
// `tile_size_cells` cells of `resolution_m << level` metres whose south-west corner is (col, row)
// times that side from the CRS origin (rows count northward, as in TMS; core/tiles/tile_grid.h).
bool meets(const v1::MapInfo& info, const v1::TileRef& tile, const std::vector<double>& box) {
  if (box.empty()) return true;
  const double side = info.resolution_m() * (1 << tile.level()) * info.tile_size_cells();
  const double west = tile.col() * side, south = tile.row() * side;
  return west < box[2] && west + side > box[0] && south < box[3] && south + side > box[1];
}

void run_tiles(const MapOptions& o) {
  const v1::TileFormat format = parse_format(o.format);
  auto stub = v1::MapService::NewStub(o.remote.channel());
  v1::GetMapInfoRequest ask;
  ask.set_job_id(o.job);
  v1::MapInfo info;
  check("GetMapInfo", stub->GetMapInfo(o.remote.context(30).get(), ask, &info));
  if (!o.bbox.empty() && info.tile_size_cells() == 0)
    throw std::runtime_error("job " + std::to_string(o.job) + " has no tile grid to select a bounding box in");
  int count = 0;
  std::int64_t bytes = 0;
  for (const v1::TileRef& tile : info.tiles()) {
    if (std::find(tile.formats().begin(), tile.formats().end(), format) == tile.formats().end()) continue;
    if (!meets(info, tile, o.bbox)) continue;
    v1::GetTileRequest request;
    request.set_job_id(o.job);
    request.set_level(tile.level());
    request.set_col(tile.col());
    request.set_row(tile.row());
    request.set_format(format);
    auto context = o.remote.context(300);
    auto reader = stub->GetTile(context.get(), request);
    std::ostringstream name;
    name << tile.level() << "/" << tile.col() << "_" << tile.row() << extension(format);
    bytes += save(reader, "GetTile " + name.str(), std::filesystem::path(o.out) / name.str());
    ++count;
  }
  std::printf("%d %s tiles (%s) of job %lld in %s (EPSG:%d)\n", count, o.format.c_str(), megabytes(bytes).c_str(),
              static_cast<long long>(o.job), o.out.c_str(), info.epsg());
}

void run_map(const MapOptions& o) {
  v1::GetMapRequest request;
  request.set_job_id(o.job);
  request.set_format(o.map_format == "bag"          ? v1::BAG
                     : o.map_format == "gsf"        ? v1::GSF
                     : o.map_format == "difference" ? v1::DIFFERENCE
                                                    : v1::COG);
  if (o.map_format == "gsf") request.set_survey(o.epoch);
  else request.set_epoch(o.epoch == 0 ? 2 : o.epoch);
  if (!o.epochs.empty()) {
    if (o.epochs.size() != 2 || o.epoch != 0 || o.map_format != "difference")
      throw std::invalid_argument("map: --epochs A,B (two surveys, with --format difference, without --epoch)");
    request.set_from_epoch(o.epochs[0]);
    request.set_epoch(o.epochs[1]);
  }
  auto context = o.remote.context();
  auto reader = v1::MapService::NewStub(o.remote.channel())->GetMap(context.get(), request);
  const std::int64_t size = save(reader, "GetMap", o.out);
  std::printf("map of job %lld: %s (%s)\n", static_cast<long long>(o.job), o.out.c_str(), megabytes(size).c_str());
}

}  // namespace

void add_map_commands(CLI::App& app) {
  auto tiles = std::make_shared<MapOptions>();
  CLI::App* cmd = app.add_subcommand("tiles", "Download a job's map tiles into OUT/<level>/<col>_<row>.<ext>");
  cmd->add_option("job", tiles->job, "job id")->required();
  cmd->add_option("--out", tiles->out, "output folder")->required();
  cmd->add_option("--format", tiles->format, "geotiff, vdb or png")->capture_default_str();
  cmd->add_option("--bbox", tiles->bbox, "only tiles meeting min_e min_n max_e max_n (CRS metres)")->expected(4);
  add_remote_options(cmd, tiles->remote);
  cmd->callback([tiles] { run_tiles(*tiles); });

  auto map = std::make_shared<MapOptions>();
  cmd = app.add_subcommand("map", "Download a job's whole map as one Cloud Optimized GeoTIFF or BAG, or its corrected GSF");
  cmd->add_option("job", map->job, "job id")->required();
  cmd->add_option("--format", map->map_format,
                  "cog (elevation, uncertainty, count), bag (elevation, uncertainty), gsf (the survey's pings "
                  "with the corrected navigation) or difference (a job of several surveys: the change from the first "
                  "to --epoch, or between --epochs A,B)")
      ->check(CLI::IsMember({"cog", "bag", "gsf", "difference"}))
      ->capture_default_str();
  cmd->add_option("--epoch", map->epoch,
                  "a job of several surveys: --format difference, the later survey's place in the job (2 to N; "
                  "default 2); --format gsf, whose corrected GSF (1 to N; default the first's)");
  cmd->add_option("--epochs", map->epochs, "--format difference: the change from survey A to survey B (A < B)")
      ->delimiter(',');
  cmd->add_option("--out", map->out, "output file (.tif, .bag or .gsf)")->required();
  add_remote_options(cmd, map->remote);
  cmd->callback([map] { run_map(*map); });
}

}  // namespace bathyslam::cli
