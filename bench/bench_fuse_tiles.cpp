// Throughput of map fusion and tiling on a simulated survey (the `lake` bundle by default), with
// the dead-reckoning poses (fusion does not care where the poses come from).
//
//   bench_fuse_tiles --bundle DIR      an existing bundle
//   bench_fuse_tiles                   simulate `lake` seed 1 into a temporary folder first
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <thread>

#include "bench/lake_bundle.h"
#include "core/fuse/fuse.h"
#include "core/io/bundle.h"
#include "core/tiles/geotiff_writer.h"
#include "core/tiles/tile_files.h"
#include "core/tiles/tile_grid.h"
#include "core/tiles/vdb_writer.h"

namespace {

namespace fs = std::filesystem;
using namespace bathyslam;

struct Input {
  std::string crs;
  SubmapSet submaps;
  std::vector<Eigen::Isometry3d> poses;
  GridRaster map;  // fused once, for the tiling benchmarks
};
Input* g_input = nullptr;

const fs::path& scratch() {
  static const fs::path dir = fs::temp_directory_path() / "bathyslam_bench_tiles";
  return dir;
}

void BM_Fuse(benchmark::State& state) {
  std::uint64_t soundings = 0;
  double cells_MB = 0;  // the fuser's per-cell accumulators
  for (auto _ : state) {
    GridFuser fuser(g_input->submaps.origin);
    for (std::size_t i = 0; i < g_input->submaps.submaps.size(); ++i) {
      fuser.add(g_input->submaps.submaps[i].points, g_input->poses[i]);
    }
    const GridRaster map = fuser.raster();
    benchmark::DoNotOptimize(map.elevation.data());
    soundings = fuser.soundings();
    cells_MB = static_cast<double>(fuser.allocated_bytes()) / 1e6;
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * soundings));
  state.counters["soundings"] = static_cast<double>(soundings);
  state.counters["cells_MB"] = cells_MB;
  state.counters["soundings/s"] = benchmark::Counter(static_cast<double>(soundings), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Fuse)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(5.0);

void report_tiles(benchmark::State& state, std::size_t tiles) {
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * tiles));
  state.counters["tiles"] = static_cast<double>(tiles);
  state.counters["tiles/s"] = benchmark::Counter(static_cast<double>(tiles), benchmark::Counter::kIsIterationInvariantRate);
}

// The pyramid alone: coarsening and cutting every tile, nothing written.
void BM_TilePyramid(benchmark::State& state) {
  std::size_t tiles = 0;
  for (auto _ : state) {
    tiles = 0;
    for_each_tile(g_input->map, [&](const TileId&, const GridRaster& tile) {
      benchmark::DoNotOptimize(tile.elevation.data());
      ++tiles;
    });
  }
  report_tiles(state, tiles);
}
BENCHMARK(BM_TilePyramid)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

// The pyramid written: a COG and a .vdb per tile.
void BM_TileFiles(benchmark::State& state) {
  TileFileCount written;
  for (auto _ : state) written = write_tile_files(g_input->map, g_input->crs, scratch() / "tiles",
                               static_cast<int>(std::thread::hardware_concurrency()));
  report_tiles(state, written.tiles);
  state.counters["levels"] = written.levels;
}
BENCHMARK(BM_TileFiles)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(5.0);

// One full level-0 tile in each format: where the tile writing time goes.
const GridRaster& fullest_tile() {
  static const GridRaster fullest = [] {
    GridRaster best;
    for_each_tile(g_input->map, [&](const TileId& id, const GridRaster& tile) {
      if (id.level == 0 && tile.valid_cells() > best.valid_cells()) best = tile;
    });
    return best;
  }();
  return fullest;
}
void BM_OneTileGeoTiff(benchmark::State& state) {
  for (auto _ : state) write_geotiff(fullest_tile(), g_input->crs, scratch() / "tile.tif");
  state.counters["cells_with_data"] = static_cast<double>(fullest_tile().valid_cells());
}
BENCHMARK(BM_OneTileGeoTiff)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
void BM_OneTileVdb(benchmark::State& state) {
  for (auto _ : state) write_vdb(fullest_tile(), g_input->crs, scratch() / "tile.vdb");
  state.counters["cells_with_data"] = static_cast<double>(fullest_tile().valid_cells());
}
BENCHMARK(BM_OneTileVdb)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

// The whole map as one COG with overviews.
void BM_MapGeoTiff(benchmark::State& state) {
  for (auto _ : state) write_geotiff(g_input->map, g_input->crs, scratch() / "map.tif");
  state.counters["cells"] = static_cast<double>(g_input->map.geometry.cells());
}
BENCHMARK(BM_MapGeoTiff)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

}  // namespace

int main(int argc, char** argv) {
  const fs::path bundle = bench::lake_bundle(argc, argv);
  std::fprintf(stderr, "reading %s and building submaps ...\n", bundle.c_str());
  Input input;
  {
    const Survey survey = load_bundle(bundle);
    input.crs = survey.metadata.crs;
    input.submaps = build_submaps(survey);
  }
  for (const Submap& s : input.submaps.submaps) input.poses.push_back(s.dr_pose);
  input.map = fuse_submaps(input.submaps, input.poses);
  std::fprintf(stderr, "map: %d x %d cells at %.2f m, %zu with data\n", input.map.geometry.width,
               input.map.geometry.height, input.map.geometry.resolution_m, input.map.valid_cells());
  g_input = &input;
  fs::create_directories(scratch());

  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  fs::remove_all(scratch());
  return 0;
}
