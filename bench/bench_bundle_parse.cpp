// Throughput of the bundle reader on a simulated survey (the `lake` bundle by default).
//
//   bench_bundle_parse --bundle DIR      parse an existing bundle
//   bench_bundle_parse                   simulate `lake` seed 1 into a temporary folder first
#include <benchmark/benchmark.h>

#include <filesystem>

#include "bench/lake_bundle.h"
#include "core/io/bundle.h"

namespace {

namespace fs = std::filesystem;
fs::path g_bundle;

std::uintmax_t bundle_bytes(const fs::path& dir) {
  std::uintmax_t bytes = 0;
  for (auto file : {bathyslam::kSurveyJsonFile, bathyslam::kNavFile, bathyslam::kPingsFile,
                    bathyslam::kReferenceNavFile}) {
    if (fs::exists(dir / file)) bytes += fs::file_size(dir / file);
  }
  return bytes;
}

void BM_ReadBundle(benchmark::State& state) {
  const std::uintmax_t bytes = bundle_bytes(g_bundle);
  std::size_t soundings = 0;
  for (auto _ : state) {
    const bathyslam::BundleReadResult result = bathyslam::read_bundle(g_bundle);
    if (!result.survey) {
      state.SkipWithError("bundle did not parse");
      return;
    }
    soundings = result.survey->beams.size();
    benchmark::DoNotOptimize(result.survey->beams.data());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes));
  state.counters["soundings"] = static_cast<double>(soundings);
  state.counters["MB"] = static_cast<double>(bytes) / 1e6;
}
BENCHMARK(BM_ReadBundle)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(5.0);

}  // namespace

int main(int argc, char** argv) {
  g_bundle = bathyslam::bench::lake_bundle(argc, argv);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
