#pragma once
// What a job produces, stored under the job: submaps, constraints, optimized poses, map tiles,
// files too large for one row (in chunks) and the quality report. Poses are stored as quaternion (w, x, y, z) + translation.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "core/pipeline/pipeline.h"
#include "core/submaps/submap.h"
#include "server/storage/database.h"
#include "server/storage/job_queue.h"

namespace bathyslam::storage {

struct TileKey {
  std::string format;  // geotiff or openvdb
  int level = 0;
  int col = 0;
  int row = 0;
};

// The tile grid of a job's map (table maps), written by the tiling stage.
struct MapGrid {
  int epsg = 0;
  double resolution_m = 0;
  double min_easting = 0, min_northing = 0, max_easting = 0, max_northing = 0;
  int tile_size_cells = 0;
  int levels = 0;
};

// A submap's time and DR pose without its points: what a trajectory needs.
struct SubmapPose {
  int index = 0;
  double time_mid = 0;
  Eigen::Isometry3d dr_pose = Eigen::Isometry3d::Identity();
};

struct Report {
  nlohmann::json report;
  std::map<std::string, Bytes> plots;  // name -> PNG
};

class ResultStore {
 public:
  // Files are stored in chunks of `chunk_bytes` (1 MiB, as uploads are).
  explicit ResultStore(ConnectionPool& pool, std::size_t chunk_bytes = 1 << 20);

  // The same store for a worker holding `lease`: every write below (the lease's job only) commits
  // only while the lease is held, else throws LeaseLost and writes nothing. A worker whose lease
  // was reaped can thus neither add its results to those of the job's next attempt nor discard them.
  ResultStore fenced(const Lease& lease) const;

  // Each save replaces nothing: it inserts in one transaction and fails (changing nothing) if
  // the job already has those rows.
  void save_submaps(std::int64_t job_id, const std::vector<Submap>& submaps);
  std::vector<Submap> load_submaps(std::int64_t job_id);  // by index
  std::vector<SubmapPose> submap_poses(std::int64_t job_id);  // by index
  // Submaps whose DR footprint meets the rectangle (map frame): the lookup of tiling.
  std::vector<int> submaps_overlapping(std::int64_t job_id, const Eigen::AlignedBox2d& area);

  // Registrations need a path ("direct" or "feature-aided"), odometry constraints have none.
  void save_constraints(std::int64_t job_id, const std::vector<Constraint>& constraints);
  std::vector<Constraint> load_constraints(std::int64_t job_id);  // in saved order

  void save_optimized_poses(std::int64_t job_id, const std::vector<Eigen::Isometry3d>& poses);  // by submap
  std::vector<Eigen::Isometry3d> load_optimized_poses(std::int64_t job_id);

  void put_tile(std::int64_t job_id, const TileKey& key, const Bytes& data);  // replaces the same key
  std::optional<Bytes> tile(std::int64_t job_id, const TileKey& key);
  std::vector<TileKey> tiles(std::int64_t job_id);  // every stored tile, without its bytes
  // A stored tile's size, and `length` of its bytes from `offset` (fewer at its end): a range of
  // the whole map (the COG) without reading the rest of it.
  std::optional<std::int64_t> tile_size(std::int64_t job_id, const TileKey& key);
  Bytes tile_bytes(std::int64_t job_id, const TileKey& key, std::int64_t offset, std::int64_t length);

  // A file product (plain name: letters, digits, '.', '_', '-'), read from `path` chunk by
  // chunk and stored in one transaction; replaces a file of that name. Memory: one chunk.
  void put_file(std::int64_t job_id, const std::string& name, const std::filesystem::path& path);
  std::optional<std::int64_t> file_size(std::int64_t job_id, const std::string& name);  // nullopt: none
  // Hands the file's chunks to `sink` in order, one query each (memory: one chunk); false when
  // there is no such file. Throws std::runtime_error when a chunk is missing.
  bool read_file(std::int64_t job_id, const std::string& name, const std::function<void(const Bytes&)>& sink);
  // `length` bytes of the file from `offset` (fewer at its end), from the chunks they span only.
  Bytes file_bytes(std::int64_t job_id, const std::string& name, std::int64_t offset, std::int64_t length);

  void save_map_grid(std::int64_t job_id, const MapGrid& grid);
  std::optional<MapGrid> map_grid(std::int64_t job_id);

  // The map frame's origin of the job's poses (the CRS minus this).
  void save_origin(std::int64_t job_id, const LocalOrigin& origin);
  std::optional<LocalOrigin> origin(std::int64_t job_id);

  void save_report(std::int64_t job_id, const Report& report);
  std::optional<Report> load_report(std::int64_t job_id);

  // The register stage's batches as a running job registers them (core/pipeline/
  // registration_checkpoint.h), for its next attempt to take up: `bytes` replaces a batch of the
  // same start. Kept by discard (an attempt killed while it stores leaves them to the next);
  // removed when the job ends (JobQueue: finish, cancel).
  void save_checkpoint(std::int64_t job_id, int batch_begin, int batch_end, const Bytes& bytes);
  std::vector<Bytes> load_checkpoints(std::int64_t job_id);  // by batch start

  // Removes everything the job stored, in one transaction: an attempt stopped halfway through
  // storing (server stopped, lease lost) leaves rows that the next attempt's saves would collide with.
  void discard(std::int64_t job_id);
  // The same, unfenced, for a job that was cancelled (true then; any other state keeps its
  // results): a cancel may land between two store steps, or after the last one, and what the
  // steps before it wrote must not be published. Waits for a store step in flight to commit.
  bool discard_if_cancelled(std::int64_t job_id);

 private:
  // Inside a write's transaction: throws LeaseLost unless the fence's lease is held.
  void check_fence(Connection& connection, std::int64_t job_id) const;
  // One statement in a transaction of its own, behind the fence.
  void write_fenced(std::int64_t job_id, std::string_view sql, std::initializer_list<Param> params);

  ConnectionPool& pool_;
  std::size_t chunk_bytes_;
  std::optional<Lease> fence_;
};

}  // namespace bathyslam::storage
