#include "server/storage/result_store.h"

#include <zlib.h>

#include <array>
#include <bit>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "core/candidates/candidates.h"

namespace bathyslam::storage {
namespace {

static_assert(std::endian::native == std::endian::little, "points are stored as little-endian float32");

std::string pose_array(const Eigen::Isometry3d& pose) {
  const Eigen::Quaterniond q(pose.rotation());
  const Eigen::Vector3d t = pose.translation();
  const std::array<double, 7> values = {q.w(), q.x(), q.y(), q.z(), t.x(), t.y(), t.z()};
  return float8_array(values.data(), values.size());
}

Eigen::Isometry3d parse_pose(std::string_view text) {
  std::vector<double> v = parse_float8_array(text);
  if (v.size() != 7) throw DatabaseError("XX000", "a pose needs 7 numbers, got " + std::to_string(v.size()));
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::Quaterniond(v[0], v[1], v[2], v[3]).normalized().toRotationMatrix();
  pose.translation() = Eigen::Vector3d(v[4], v[5], v[6]);
  return pose;
}

// float32 triples with their bytes in planes (every float's first byte, then every second ...),
// which the column compresses (LZ4: migration 0014): the planes of signs, exponents and high
// mantissas repeat, where the interleaved floats gave LZ4 nothing. Deflating the floats here cost
// more than storing them ("f32le+zlib", still read).
std::pair<std::string, Bytes> encode_points(const std::vector<Eigen::Vector3f>& points) {
  const std::size_t floats = points.size() * 3;
  Bytes planes(floats * 4);
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      std::uint8_t bytes[4];
      std::memcpy(bytes, &points[i][axis], 4);
      for (int k = 0; k < 4; ++k) planes[k * floats + i * 3 + axis] = bytes[k];
    }
  }
  return {"f32le-planes", std::move(planes)};
}

std::vector<Eigen::Vector3f> decode_points(std::string_view encoding, const Bytes& data, std::size_t count) {
  Bytes raw;
  if (encoding == "f32le+zlib") {
    raw.resize(count * 12);
    uLongf size = raw.size();
    if (uncompress(raw.data(), &size, data.data(), data.size()) != Z_OK || size != raw.size())
      throw std::runtime_error("submap points: corrupt zlib data");
  } else if (encoding == "f32le") {
    raw = data;
  } else if (encoding == "f32le-planes") {
    if (data.size() != count * 12) throw std::runtime_error("submap points: size does not match the point count");
    raw.resize(data.size());
    const std::size_t floats = count * 3;
    for (std::size_t f = 0; f < floats; ++f) {
      for (int k = 0; k < 4; ++k) raw[f * 4 + k] = data[k * floats + f];
    }
  } else {
    throw std::runtime_error("submap points: unknown encoding '" + std::string(encoding) + "'");
  }
  if (raw.size() != count * 12) throw std::runtime_error("submap points: size does not match the point count");
  std::vector<Eigen::Vector3f> points(count);
  for (std::size_t i = 0; i < count; ++i) std::memcpy(points[i].data(), raw.data() + i * 12, 12);
  return points;
}

std::string polygon(const Footprint& footprint) {
  std::string text = "(";
  for (std::size_t k = 0; k < footprint.corners.size(); ++k) {
    if (k) text += ',';
    text += "(" + float8_array(footprint.corners[k].data(), 2).substr(1);
    text.back() = ')';
  }
  return text + ")";
}


}  // namespace

void ResultStore::save_submaps(std::int64_t job_id, const std::vector<Submap>& submaps) {
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  check_fence(*connection, job_id);
  for (const Submap& submap : submaps) {
    auto [encoding, points] = encode_points(submap.points);
    std::optional<std::string> reference;
    if (submap.reference_pose) reference = pose_array(*submap.reference_pose);
    connection->exec(
        "INSERT INTO submaps (job_id, idx, line, time_begin, time_mid, time_end, dr_pose, reference_pose,"
        " footprint, point_count, points_encoding, points)"
        " VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12)",
        {job_id, submap.index, submap.line, submap.time_begin, submap.time_mid, submap.time_end,
         pose_array(submap.dr_pose), reference, polygon(footprint_of(submap, submap.dr_pose)), submap.points.size(),
         encoding, points});
  }
  transaction.commit();
}

std::vector<Submap> ResultStore::load_submaps(std::int64_t job_id) {
  auto connection = pool_.acquire();
  Result rows = connection->exec(
      "SELECT idx, line, time_begin, time_mid, time_end, dr_pose, reference_pose, point_count, points_encoding, points"
      " FROM submaps WHERE job_id = $1 ORDER BY idx",
      {job_id});
  std::vector<Submap> submaps(rows.rows());
  for (int row = 0; row < rows.rows(); ++row) {
    Submap& s = submaps[row];
    s.index = static_cast<int>(rows.int64(row, "idx"));
    s.line = static_cast<int>(rows.int64(row, "line"));
    s.time_begin = rows.float8(row, "time_begin");
    s.time_mid = rows.float8(row, "time_mid");
    s.time_end = rows.float8(row, "time_end");
    s.dr_pose = parse_pose(rows.text(row, "dr_pose"));
    if (!rows.is_null(row, "reference_pose")) s.reference_pose = parse_pose(rows.text(row, "reference_pose"));
    s.points = decode_points(rows.text(row, "points_encoding"), rows.bytes(row, "points"),
                             static_cast<std::size_t>(rows.int64(row, "point_count")));
  }
  return submaps;
}

std::vector<int> ResultStore::submaps_overlapping(std::int64_t job_id, const Eigen::AlignedBox2d& area) {
  auto connection = pool_.acquire();
  const std::array<double, 4> corners = {area.min().x(), area.min().y(), area.max().x(), area.max().y()};
  Result rows = connection->exec(
      "SELECT idx FROM submaps WHERE job_id = $1"
      " AND footprint && box(point($2, $3), point($4, $5))::polygon ORDER BY idx",
      {job_id, corners[0], corners[1], corners[2], corners[3]});
  std::vector<int> indices;
  for (int row = 0; row < rows.rows(); ++row) indices.push_back(static_cast<int>(rows.int64(row, "idx")));
  return indices;
}

namespace {

// The constraints table's columns besides job_id: constraint_row binds them in this order and
// constraint_from reads them by name.
constexpr std::array<const char*, 23> kConstraintColumns = {
    "idx",        "type",           "path",           "from_submap",      "to_submap",     "measured",
    "information", "converged",     "fitness",        "overlap_points",   "overlap_mse_m2", "overlap_fraction",
    "accepted",   "rejection",      "reason",         "exclusion",        "exclusion_reason", "anchor",
    "path_reason", "feature_density", "matches",      "inlier_ratio",     "guess"};

std::vector<Param> constraint_row(std::int64_t job_id, std::size_t idx, const Constraint& c) {
  // Row-major, the order a reader of the table expects.
  const Eigen::Matrix<double, 6, 6, Eigen::RowMajor> information = c.information;
  std::optional<std::string> path;
  if (c.path) path = to_string(*c.path);
  return {job_id, idx, bathyslam::to_string(c.type), path, c.from, c.to, pose_array(c.measured),
          float8_array(information.data(), 36), c.quality.converged, c.quality.fitness, c.quality.overlap_points,
          c.quality.overlap_mse_m2, c.overlap_fraction, c.accepted(), to_string(c.rejection.kind), c.rejection.detail,
          to_string(c.exclusion.kind), c.exclusion.detail, float8_array(c.anchor.data(), 3), c.path_reason,
          c.feature_density, c.matches, c.inlier_ratio, pose_array(c.guess)};
}

Constraint constraint_from(const Result& rows, int row) {
  Constraint c;
  c.type = parse_constraint_type(std::string(rows.text(row, "type")));
  if (const auto path = rows.optional_text(row, "path")) c.path = parse_registration_path(*path);
  c.from = static_cast<int>(rows.int64(row, "from_submap"));
  c.to = static_cast<int>(rows.int64(row, "to_submap"));
  c.measured = parse_pose(rows.text(row, "measured"));
  c.guess = parse_pose(rows.text(row, "guess"));
  const std::vector<double> information = parse_float8_array(rows.text(row, "information"));
  if (information.size() != 36) throw std::runtime_error("an information matrix needs 36 numbers");
  c.information = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(information.data());
  c.quality.converged = rows.boolean(row, "converged");
  c.quality.fitness = rows.float8(row, "fitness");
  c.quality.overlap_points = static_cast<std::size_t>(rows.int64(row, "overlap_points"));
  c.quality.overlap_mse_m2 = rows.float8(row, "overlap_mse_m2");
  c.overlap_fraction = rows.float8(row, "overlap_fraction");
  c.rejection = {parse_rejection_kind(std::string(rows.text(row, "rejection"))), std::string(rows.text(row, "reason"))};
  c.exclusion = {parse_rejection_kind(std::string(rows.text(row, "exclusion"))),
                 std::string(rows.text(row, "exclusion_reason"))};
  const std::vector<double> anchor = parse_float8_array(rows.text(row, "anchor"));
  if (anchor.size() != 3) throw std::runtime_error("an anchor needs 3 numbers");
  c.anchor = Eigen::Vector3d(anchor[0], anchor[1], anchor[2]);
  c.path_reason = rows.text(row, "path_reason");
  c.feature_density = rows.float8(row, "feature_density");
  c.matches = static_cast<int>(rows.int64(row, "matches"));
  c.inlier_ratio = rows.float8(row, "inlier_ratio");
  return c;
}

// INSERT INTO constraints (job_id, idx, ...) VALUES ($1, $2, ...).
std::string constraint_insert() {
  std::string columns = "job_id", values = "$1";
  for (std::size_t k = 0; k < kConstraintColumns.size(); ++k) {
    columns += std::string(", ") + kConstraintColumns[k];
    values += ", $" + std::to_string(k + 2);
  }
  return "INSERT INTO constraints (" + columns + ") VALUES (" + values + ")";
}

}  // namespace

void ResultStore::save_constraints(std::int64_t job_id, const std::vector<Constraint>& constraints) {
  static const std::string insert = constraint_insert();
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  check_fence(*connection, job_id);
  for (std::size_t i = 0; i < constraints.size(); ++i) {
    const Constraint& c = constraints[i];
    if (from_navigation(c.type) == c.path.has_value())
      throw std::invalid_argument("constraint " + std::to_string(i) +
                                  ": odometry constraints have no registration path, registrations need one");
    connection->exec(insert, constraint_row(job_id, i, c));
  }
  transaction.commit();
}

std::vector<Constraint> ResultStore::load_constraints(std::int64_t job_id) {
  auto connection = pool_.acquire();
  const Result rows = connection->exec("SELECT * FROM constraints WHERE job_id = $1 ORDER BY idx", {job_id});
  std::vector<Constraint> constraints;
  for (int row = 0; row < rows.rows(); ++row) constraints.push_back(constraint_from(rows, row));
  return constraints;
}

void ResultStore::save_optimized_poses(std::int64_t job_id, const std::vector<Eigen::Isometry3d>& poses) {
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  check_fence(*connection, job_id);
  for (std::size_t i = 0; i < poses.size(); ++i)
    connection->exec("INSERT INTO optimized_poses (job_id, submap, pose) VALUES ($1, $2, $3)",
                     {job_id, i, pose_array(poses[i])});
  transaction.commit();
}

std::vector<Eigen::Isometry3d> ResultStore::load_optimized_poses(std::int64_t job_id) {
  auto connection = pool_.acquire();
  Result rows = connection->exec("SELECT submap, pose FROM optimized_poses WHERE job_id = $1 ORDER BY submap", {job_id});
  std::vector<Eigen::Isometry3d> poses;
  for (int row = 0; row < rows.rows(); ++row) {
    if (rows.int64(row, "submap") != row) throw std::runtime_error("optimized poses of job " + std::to_string(job_id) + " have a gap");
    poses.push_back(parse_pose(rows.text(row, "pose")));
  }
  return poses;
}

void ResultStore::put_tile(std::int64_t job_id, const TileKey& key, const Bytes& data) {
  if (key.format != "geotiff" && key.format != "openvdb" && key.format != "png" && key.format != "cog" && key.format != "bag")
    throw std::invalid_argument("tile format '" + key.format + "': geotiff, openvdb, png, cog or bag");
  if (key.level < 0) throw std::invalid_argument("tile level must be non-negative");
  write_fenced(job_id,
               "INSERT INTO tiles (job_id, format, level, tile_col, tile_row, data) VALUES ($1, $2, $3, $4, $5, $6)"
               " ON CONFLICT (job_id, format, level, tile_col, tile_row) DO UPDATE SET data = EXCLUDED.data",
               {job_id, key.format, key.level, key.col, key.row, data});
}

std::optional<Bytes> ResultStore::tile(std::int64_t job_id, const TileKey& key) {
  auto connection = pool_.acquire();
  Result row = connection->exec(
      "SELECT data FROM tiles WHERE job_id = $1 AND format = $2 AND level = $3 AND tile_col = $4 AND tile_row = $5",
      {job_id, key.format, key.level, key.col, key.row});
  if (row.rows() == 0) return std::nullopt;
  return row.bytes(0, "data");
}

std::optional<std::int64_t> ResultStore::tile_size(std::int64_t job_id, const TileKey& key) {
  auto connection = pool_.acquire();
  Result row = connection->exec(
      "SELECT octet_length(data) AS size FROM tiles"
      " WHERE job_id = $1 AND format = $2 AND level = $3 AND tile_col = $4 AND tile_row = $5",
      {job_id, key.format, key.level, key.col, key.row});
  if (row.rows() == 0) return std::nullopt;
  return row.int64(0, "size");
}

Bytes ResultStore::tile_bytes(std::int64_t job_id, const TileKey& key, std::int64_t offset, std::int64_t length) {
  auto connection = pool_.acquire();
  // substring() of an uncompressed TOAST value reads only the chunks it spans (a COG's deflated
  // bytes are stored uncompressed: PostgreSQL's compression gains nothing on them).
  Result row = connection->exec(
      "SELECT substring(data FROM $6 FOR $7) AS data FROM tiles"
      " WHERE job_id = $1 AND format = $2 AND level = $3 AND tile_col = $4 AND tile_row = $5",
      {job_id, key.format, key.level, key.col, key.row, offset + 1, length});
  if (row.rows() == 0) return {};
  return row.bytes(0, "data");
}

std::vector<SubmapPose> ResultStore::submap_poses(std::int64_t job_id) {
  auto connection = pool_.acquire();
  Result rows = connection->exec("SELECT idx, time_mid, dr_pose FROM submaps WHERE job_id = $1 ORDER BY idx", {job_id});
  std::vector<SubmapPose> poses;
  for (int row = 0; row < rows.rows(); ++row)
    poses.push_back({static_cast<int>(rows.int64(row, "idx")), rows.float8(row, "time_mid"), parse_pose(rows.text(row, "dr_pose"))});
  return poses;
}

std::vector<TileKey> ResultStore::tiles(std::int64_t job_id) {
  auto connection = pool_.acquire();
  Result rows = connection->exec(
      "SELECT format, level, tile_col, tile_row FROM tiles WHERE job_id = $1 ORDER BY level, tile_row, tile_col, format",
      {job_id});
  std::vector<TileKey> keys;
  for (int row = 0; row < rows.rows(); ++row)
    keys.push_back({std::string(rows.text(row, "format")), static_cast<int>(rows.int64(row, "level")),
                    static_cast<int>(rows.int64(row, "tile_col")), static_cast<int>(rows.int64(row, "tile_row"))});
  return keys;
}

ResultStore::ResultStore(ConnectionPool& pool, std::size_t chunk_bytes) : pool_(pool), chunk_bytes_(chunk_bytes) {
  if (chunk_bytes_ == 0) throw std::invalid_argument("result store: chunk size must be positive");
}

void ResultStore::put_file(std::int64_t job_id, const std::string& name, const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot read");
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  check_fence(*connection, job_id);
  connection->exec("DELETE FROM job_files WHERE job_id = $1 AND name = $2", {job_id, name});
  // The row first (the chunks refer to it), its size and count once every chunk is in.
  connection->exec("INSERT INTO job_files (job_id, name, size_bytes, chunk_count) VALUES ($1, $2, 0, 0)", {job_id, name});
  std::int64_t size = 0, chunks = 0;
  Bytes chunk(chunk_bytes_);
  while (in.read(reinterpret_cast<char*>(chunk.data()), static_cast<std::streamsize>(chunk.size())) || in.gcount() > 0) {
    const Bytes data(chunk.begin(), chunk.begin() + in.gcount());
    connection->exec("INSERT INTO job_file_chunks (job_id, name, seq, data) VALUES ($1, $2, $3, $4)",
                     {job_id, name, chunks++, data});
    size += static_cast<std::int64_t>(data.size());
  }
  if (in.bad()) throw std::runtime_error(path.string() + ": cannot read");
  connection->exec("UPDATE job_files SET size_bytes = $3, chunk_count = $4 WHERE job_id = $1 AND name = $2",
                   {job_id, name, size, chunks});
  transaction.commit();
}

std::optional<std::int64_t> ResultStore::file_size(std::int64_t job_id, const std::string& name) {
  auto connection = pool_.acquire();
  Result row = connection->exec("SELECT size_bytes FROM job_files WHERE job_id = $1 AND name = $2", {job_id, name});
  if (row.rows() == 0) return std::nullopt;
  return row.int64(0, "size_bytes");
}

bool ResultStore::read_file(std::int64_t job_id, const std::string& name, const std::function<void(const Bytes&)>& sink) {
  auto connection = pool_.acquire();
  Result head = connection->exec("SELECT chunk_count FROM job_files WHERE job_id = $1 AND name = $2", {job_id, name});
  if (head.rows() == 0) return false;
  const std::int64_t chunks = head.int64(0, "chunk_count");
  for (std::int64_t seq = 0; seq < chunks; ++seq) {
    Result chunk = connection->exec("SELECT data FROM job_file_chunks WHERE job_id = $1 AND name = $2 AND seq = $3",
                                    {job_id, name, seq});
    if (chunk.rows() == 0)
      throw std::runtime_error("job " + std::to_string(job_id) + " file '" + name + "': chunk " + std::to_string(seq) + " is missing");
    sink(chunk.bytes(0, "data"));
  }
  return true;
}

Bytes ResultStore::file_bytes(std::int64_t job_id, const std::string& name, std::int64_t offset, std::int64_t length) {
  auto connection = pool_.acquire();
  // Every chunk but the last holds as many bytes as the first (put_file).
  Result first = connection->exec(
      "SELECT octet_length(data) AS size FROM job_file_chunks WHERE job_id = $1 AND name = $2 AND seq = 0", {job_id, name});
  if (first.rows() == 0 || length <= 0) return {};
  const std::int64_t chunk = std::max<std::int64_t>(1, first.int64(0, "size"));
  Result rows = connection->exec(
      "SELECT seq, data FROM job_file_chunks WHERE job_id = $1 AND name = $2 AND seq BETWEEN $3 AND $4 ORDER BY seq",
      {job_id, name, offset / chunk, (offset + length - 1) / chunk});
  Bytes out;
  for (int row = 0; row < rows.rows(); ++row) {
    const Bytes data = rows.bytes(row, "data");
    const std::int64_t start = rows.int64(row, "seq") * chunk;
    const std::int64_t from = std::max(offset, start) - start;
    const std::int64_t to = std::min<std::int64_t>(offset + length - start, static_cast<std::int64_t>(data.size()));
    if (from < to) out.insert(out.end(), data.begin() + from, data.begin() + to);
  }
  return out;
}

void ResultStore::save_map_grid(std::int64_t job_id, const MapGrid& g) {
  write_fenced(job_id,
               "INSERT INTO maps (job_id, epsg, resolution_m, min_easting, min_northing, max_easting, max_northing,"
               " tile_size_cells, levels) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9)",
               {job_id, g.epsg, g.resolution_m, g.min_easting, g.min_northing, g.max_easting, g.max_northing,
                g.tile_size_cells, g.levels});
}

std::optional<MapGrid> ResultStore::map_grid(std::int64_t job_id) {
  auto connection = pool_.acquire();
  Result row = connection->exec(
      "SELECT epsg, resolution_m, min_easting, min_northing, max_easting, max_northing, tile_size_cells, levels"
      " FROM maps WHERE job_id = $1",
      {job_id});
  if (row.rows() == 0) return std::nullopt;
  MapGrid g;
  g.epsg = static_cast<int>(row.int64(0, "epsg"));
  g.resolution_m = row.float8(0, "resolution_m");
  g.min_easting = row.float8(0, "min_easting");
  g.min_northing = row.float8(0, "min_northing");
  g.max_easting = row.float8(0, "max_easting");
  g.max_northing = row.float8(0, "max_northing");
  g.tile_size_cells = static_cast<int>(row.int64(0, "tile_size_cells"));
  g.levels = static_cast<int>(row.int64(0, "levels"));
  return g;
}

void ResultStore::save_origin(std::int64_t job_id, const LocalOrigin& origin) {
  write_fenced(job_id, "UPDATE jobs SET origin_easting = $2, origin_northing = $3 WHERE id = $1",
               {job_id, origin.easting, origin.northing});
}

ResultStore ResultStore::fenced(const Lease& lease) const {
  ResultStore store(pool_, chunk_bytes_);
  store.fence_ = lease;
  return store;
}

void ResultStore::check_fence(Connection& connection, std::int64_t job_id) const {
  if (!fence_) return;
  if (job_id != fence_->job_id)
    throw std::invalid_argument("a store fenced by job " + std::to_string(fence_->job_id) + " cannot write job " +
                                std::to_string(job_id));
  if (!hold_lease(connection, *fence_)) throw LeaseLost(*fence_);
}

void ResultStore::write_fenced(std::int64_t job_id, std::string_view sql, std::initializer_list<Param> params) {
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  check_fence(*connection, job_id);
  connection->exec(sql, params);
  transaction.commit();
}

std::optional<LocalOrigin> ResultStore::origin(std::int64_t job_id) {
  auto connection = pool_.acquire();
  Result row = connection->exec(
      "SELECT origin_easting, origin_northing FROM jobs WHERE id = $1 AND origin_easting IS NOT NULL", {job_id});
  if (row.rows() == 0) return std::nullopt;
  LocalOrigin origin;
  origin.easting = row.float8(0, "origin_easting");
  origin.northing = row.float8(0, "origin_northing");
  return origin;
}

namespace {

// Everything a job stored, inside the caller's transaction, but its registration checkpoints
// (an attempt that stores its results again keeps them; JobQueue removes them when the job ends).
void delete_results(Connection& connection, std::int64_t job_id) {
  // report_plots go with their report, job_file_chunks with their file (ON DELETE CASCADE).
  for (const char* table : {"reports", "maps", "tiles", "job_files", "optimized_poses", "constraints", "submaps"})
    connection.exec(std::string("DELETE FROM ") + table + " WHERE job_id = $1", {job_id});
  connection.exec("UPDATE jobs SET origin_easting = NULL, origin_northing = NULL WHERE id = $1", {job_id});
}

}  // namespace

void ResultStore::discard(std::int64_t job_id) {
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  check_fence(*connection, job_id);
  delete_results(*connection, job_id);
  transaction.commit();
}

bool ResultStore::discard_if_cancelled(std::int64_t job_id) {
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  // FOR UPDATE conflicts with the FOR KEY SHARE of a store step in flight (hold_lease): this
  // waits for that step to commit, so that no row of it lands after the removal.
  const Result job = connection->exec("SELECT state FROM jobs WHERE id = $1 FOR UPDATE", {job_id});
  if (job.rows() == 0 || parse_job_state(job.text(0, "state")) != JobState::kCancelled) return false;
  delete_results(*connection, job_id);
  transaction.commit();
  return true;
}

void ResultStore::save_report(std::int64_t job_id, const Report& report) {
  if (!report.report.is_object()) throw std::invalid_argument("a report must be a JSON object");
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  check_fence(*connection, job_id);
  connection->exec("INSERT INTO reports (job_id, report) VALUES ($1, $2)", {job_id, report.report.dump()});
  for (const auto& [name, png] : report.plots)
    connection->exec("INSERT INTO report_plots (job_id, name, png) VALUES ($1, $2, $3)", {job_id, name, png});
  transaction.commit();
}

std::optional<Report> ResultStore::load_report(std::int64_t job_id) {
  auto connection = pool_.acquire();
  Result head = connection->exec("SELECT report FROM reports WHERE job_id = $1", {job_id});
  if (head.rows() == 0) return std::nullopt;
  Report report{nlohmann::json::parse(head.text(0, "report")), {}};
  Result plots = connection->exec("SELECT name, png FROM report_plots WHERE job_id = $1", {job_id});
  for (int row = 0; row < plots.rows(); ++row) report.plots[std::string(plots.text(row, "name"))] = plots.bytes(row, "png");
  return report;
}

void ResultStore::save_checkpoint(std::int64_t job_id, int batch_begin, int batch_end, const Bytes& bytes) {
  write_fenced(job_id,
               "INSERT INTO job_checkpoints (job_id, batch_begin, batch_end, data) VALUES ($1, $2, $3, $4)"
               " ON CONFLICT (job_id, batch_begin) DO UPDATE SET batch_end = EXCLUDED.batch_end, data = EXCLUDED.data",
               {job_id, batch_begin, batch_end, bytes});
}

std::vector<Bytes> ResultStore::load_checkpoints(std::int64_t job_id) {
  auto connection = pool_.acquire();
  const Result rows = connection->exec("SELECT data FROM job_checkpoints WHERE job_id = $1 ORDER BY batch_begin", {job_id});
  std::vector<Bytes> batches;
  for (int row = 0; row < rows.rows(); ++row) batches.push_back(rows.bytes(row, "data"));
  return batches;
}

}  // namespace bathyslam::storage
