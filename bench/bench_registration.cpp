// PCL's GICP against ours on the same submap pairs of a simulated survey (the `lake` bundle of
// seed 1 by default): time per pair and accuracy against the reference navigation, in one run.
//
//   bench_registration [--bundle DIR] [--max-pairs N] [--benchmark_filter=...]
//
// --max-pairs N keeps N pairs spread evenly over all candidates (default: all).
//
// Pairs: every adjacent-line and loop candidate at the reference poses. Each pair's guess is its
// true relative pose moved by a deterministic draw of a batch's drift (1.5 m horizontally per
// axis, 0.2 m in depth, 1.5 deg of yaw, standard deviations); the mchs switch then picks the path
// (direct from the guess, or feature-aided from RANSAC's estimate) exactly as the pipeline does,
// and only the GICP step that follows is timed, with the settings that path uses. Ours registers
// on submaps prepared once (gicp_cloud.h): their column grids are timed on their own and reported
// as a share per pair ("amortised"); the normals, computed on first use, fall in the pairs' times.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <string>

#include "bench/lake_bundle.h"
#include "core/io/bundle.h"
#include "core/parallel/parallel_for.h"
#include "core/pipeline/pipeline.h"
#include "core/register/gicp_solver.h"

namespace {

using namespace bathyslam;
using Clock = std::chrono::steady_clock;

struct Pair {
  int target = 0, source = 0;
  std::string type;  // adjacent or loop
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  CoarseStart coarse;
};

struct Input {
  std::vector<Cloud::Ptr> clouds;
  std::vector<Pair> pairs;
  double crop_margin_m = 1.0;
};
Input* g_input = nullptr;

// Times are the process's CPU time (all its threads) and the wall clock: on a shared machine the
// wall clock measures the other jobs as much as the registration, CPU time does not.
struct Outcome {
  std::vector<double> seconds, cpu_seconds, translation_m, yaw_deg;  // per pair
  double prepare_seconds = 0, prepare_cpu_seconds = 0;               // ours: the grids of all submaps used
  double all_pairs_seconds = 0, all_pairs_cpu_seconds = 0;           // pairs in parallel: the whole set, grids included
};

struct Stopwatch {
  Clock::time_point wall = Clock::now();
  std::clock_t cpu = std::clock();
  double wall_seconds() const { return std::chrono::duration<double>(Clock::now() - wall).count(); }
  double cpu_seconds() const { return static_cast<double>(std::clock() - cpu) / CLOCKS_PER_SEC; }
};
std::map<std::string, Outcome> g_outcomes;

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(p * (v.size() - 1) + 0.5)];
}

std::string load() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

// Error of a registration at the overlap (its anchor), where the pipeline's edges compare it,
// and in yaw.
void record_error(Outcome& o, const Pair& pair, const PairRegistration& r) {
  o.translation_m.push_back((r.registration.source_to_target * r.anchor - pair.truth * r.anchor).norm());
  const Eigen::Matrix3d delta = pair.truth.rotation().transpose() * r.registration.source_to_target.rotation();
  o.yaw_deg.push_back(std::abs(std::atan2(delta(1, 0), delta(0, 0))) * 180 / M_PI);
}

void record(Outcome& o, const Pair& pair, const PairRegistration& r, const Stopwatch& watch) {
  o.seconds.push_back(watch.wall_seconds());
  o.cpu_seconds.push_back(watch.cpu_seconds());
  record_error(o, pair, r);
}

void counters(benchmark::State& state, const Outcome& o) {
  state.counters["pairs"] = static_cast<double>(o.seconds.size());
  state.counters["cpu_ms_p50"] = 1e3 * percentile(o.cpu_seconds, 0.5);
  state.counters["cpu_ms_p90"] = 1e3 * percentile(o.cpu_seconds, 0.9);
  state.counters["wall_ms_p50"] = 1e3 * percentile(o.seconds, 0.5);
  state.counters["prep_cpu_ms_pair"] = o.seconds.empty() ? 0 : 1e3 * o.prepare_cpu_seconds / o.seconds.size();
  state.counters["t_err_p50_m"] = percentile(o.translation_m, 0.5);
  state.counters["t_err_p90_m"] = percentile(o.translation_m, 0.9);
  state.counters["yaw_p50_deg"] = percentile(o.yaw_deg, 0.5);
  state.counters["yaw_p90_deg"] = percentile(o.yaw_deg, 0.9);
}

void BM_PclGicp(benchmark::State& state) {
  Outcome o;
  for (auto _ : state) {
    o = {};
    for (const Pair& pair : g_input->pairs) {
      const Stopwatch watch;
      const PairRegistration r = register_direct(pcl_pair(*g_input->clouds[pair.target], *g_input->clouds[pair.source]),
                                                 pair.coarse.start, pair.coarse.gicp, g_input->crop_margin_m);
      record(o, pair, r, watch);
    }
  }
  counters(state, o);
  g_outcomes["pcl"] = o;
}
BENCHMARK(BM_PclGicp)->Unit(benchmark::kSecond)->Iterations(1);

// Ours on `threads` threads inside each registration, registering one sounding in
// `soundings_per_sample` (gicp_cloud.h; 0: the pipeline's setting).
Outcome run_own(benchmark::State& state, int threads, double soundings_per_sample) {
  Outcome o;
  for (auto _ : state) {
    o = {};
    std::map<int, std::shared_ptr<const GicpCloud>> prepared;
    auto config = [&](const Pair& pair) {
      GicpConfig gicp = pair.coarse.gicp;
      gicp.threads = threads;
      if (soundings_per_sample > 0) gicp.soundings_per_sample = soundings_per_sample;
      return gicp;
    };
    for (const Pair& pair : g_input->pairs) {
      for (int submap : {pair.target, pair.source}) {
        if (prepared.count(submap)) continue;
        const Stopwatch watch;
        prepared[submap] = prepare_gicp_cloud(*g_input->clouds[submap], config(pair));
        o.prepare_seconds += watch.wall_seconds();
        o.prepare_cpu_seconds += watch.cpu_seconds();
      }
    }
    for (const Pair& pair : g_input->pairs) {
      const Stopwatch watch;
      const PairRegistration r =
          register_direct(PairClouds{prepared[pair.target].get(), prepared[pair.source].get()}, pair.coarse.start,
                          config(pair), g_input->crop_margin_m);
      record(o, pair, r, watch);
    }
  }
  counters(state, o);
  return o;
}

void BM_OwnGicp(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  g_outcomes["ours_" + std::to_string(threads)] = run_own(state, threads, 0);
}
BENCHMARK(BM_OwnGicp)->Arg(1)->Arg(2)->Unit(benchmark::kSecond)->Iterations(1);

// Ours on one thread registering every sounding, as PCL's does: what the sample buys apart.
void BM_OwnGicpEverySounding(benchmark::State& state) { g_outcomes["ours_all_1"] = run_own(state, 1, 1); }
BENCHMARK(BM_OwnGicpEverySounding)->Unit(benchmark::kSecond)->Iterations(1);

// Ours as the pipeline spends its threads: each registration on one thread, the pairs spread
// over `threads` (register_pairs' parallel_for), the submaps prepared in the same loop before
// the pairs, as there (the GicpCloudCache). Only the wall clock of the whole set means anything here.
void BM_OwnGicpPairsInParallel(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  Outcome o;
  for (auto _ : state) {
    o = {};
    GicpCloudCache cache(g_input->clouds, g_input->pairs.front().coarse.gicp);
    std::vector<PairRegistration> results(g_input->pairs.size());
    // As register_pairs: the pairs' submaps first, then the pairs, in one loop.
    std::vector<int> submaps;
    for (const Pair& pair : g_input->pairs) submaps.insert(submaps.end(), {pair.target, pair.source});
    std::sort(submaps.begin(), submaps.end());
    submaps.erase(std::unique(submaps.begin(), submaps.end()), submaps.end());
    const Stopwatch watch;
    parallel_for(submaps.size() + g_input->pairs.size(), threads, nullptr, [&](std::size_t k) {
      if (k < submaps.size()) {
        cache.at(static_cast<std::size_t>(submaps[k]));
        return;
      }
      k -= submaps.size();
      const Pair& pair = g_input->pairs[k];
      GicpConfig gicp = pair.coarse.gicp;
      gicp.threads = 1;
      results[k] = register_direct(PairClouds{&cache.at(pair.target), &cache.at(pair.source)}, pair.coarse.start, gicp,
                                   g_input->crop_margin_m);
    });
    o.all_pairs_seconds = watch.wall_seconds();
    o.all_pairs_cpu_seconds = watch.cpu_seconds();
    for (std::size_t k = 0; k < results.size(); ++k) record_error(o, g_input->pairs[k], results[k]);
  }
  state.counters["pairs"] = static_cast<double>(o.translation_m.size());
  state.counters["all_pairs_wall_s"] = o.all_pairs_seconds;
  state.counters["all_pairs_cpu_s"] = o.all_pairs_cpu_seconds;
  state.counters["t_err_p50_m"] = percentile(o.translation_m, 0.5);
  g_outcomes["pairs_in_parallel_" + std::to_string(threads)] = o;
}
BENCHMARK(BM_OwnGicpPairsInParallel)->Arg(1)->Arg(2)->Unit(benchmark::kSecond)->Iterations(1);

Input make_input(const std::filesystem::path& bundle, std::size_t max_pairs) {
  Survey survey = load_bundle(bundle);
  PipelineConfig config;
  config.configuration = Configuration::kMchs;
  const SubmapSet set = build_submaps(survey, config.submaps);
  const std::vector<Eigen::Isometry3d> truth = bench::reference_poses(set);
  Input in;
  in.crop_margin_m = config.registration.crop_margin_m;
  std::vector<SubmapFeatures> features(set.submaps.size());
  in.clouds.resize(set.submaps.size());
#pragma omp parallel for schedule(dynamic, 4)
  for (std::size_t i = 0; i < set.submaps.size(); ++i) {
    in.clouds[i] = voxel_filter(set.submaps[i].points, config.voxel);
    features[i] = extract_features(set.submaps[i], config.grid, config.keypoints);
  }
  std::mt19937_64 rng(1);
  std::normal_distribution<double> horizontal(0, 1.5), depth(0, 0.2), yaw(0, 1.5 * M_PI / 180);
  auto add = [&](const std::vector<CandidatePair>& found, const std::string& type) {
    for (const CandidatePair& c : found) {
      Pair p{c.target, c.source, type, truth[c.target].inverse() * truth[c.source], {}};
      Eigen::Isometry3d drift = Eigen::Isometry3d::Identity();
      drift.translation() = Eigen::Vector3d(horizontal(rng), horizontal(rng), depth(rng));
      drift.linear() = Eigen::AngleAxisd(yaw(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      const uint64_t seed = config.registration.ransac.seed ^ (static_cast<uint64_t>(c.target) << 32 | static_cast<uint64_t>(c.source));
      p.coarse = coarse_start(features[c.target], features[c.source], drift * p.truth, config.registration, seed);
      in.pairs.push_back(p);
    }
  };
  add(adjacent_line_candidates(set, truth, config.candidates), "adjacent");
  add(loop_candidates(set, truth, config.candidates), "loop");
  if (in.pairs.size() > max_pairs) {  // evenly spread over the survey and both kinds
    std::vector<Pair> kept;
    for (std::size_t k = 0; k < max_pairs; ++k) kept.push_back(in.pairs[k * in.pairs.size() / max_pairs]);
    in.pairs = std::move(kept);
  }
  return in;
}

std::size_t take_max_pairs(int& argc, char** argv) {
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--max-pairs") == 0) {
      const std::size_t n = std::stoul(argv[i + 1]);
      for (int j = i; j + 2 <= argc; ++j) argv[j] = argv[j + 2];
      argc -= 2;
      return n;
    }
  }
  return static_cast<std::size_t>(-1);
}

void summary() {
  const auto pcl = g_outcomes.find("pcl");
  if (pcl == g_outcomes.end()) return;
  std::map<std::string, int> kinds;
  for (const Pair& p : g_input->pairs) ++kinds[p.type + " " + to_string(p.coarse.path)];
  std::printf("\npairs:");
  for (const auto& [kind, n] : kinds) std::printf("  %s %d", kind.c_str(), n);
  std::printf("\n%-8s %8s %8s %8s %10s %8s %9s %9s %9s %9s %9s\n", "engine", "cpu p50", "cpu p90", "+grids", "x PCL p50",
              "wall p50", "t p50 m", "t p90 m", "yaw p50", "yaw p90", "sum cpu");
  const double pcl_p50 = percentile(pcl->second.cpu_seconds, 0.5);
  for (const auto& [name, o] : g_outcomes) {
    if (name.rfind("pairs_in_parallel", 0) == 0) continue;  // one wall clock, no per-pair times
    const double grids = o.seconds.empty() ? 0 : o.prepare_cpu_seconds / o.seconds.size();
    const double p50 = percentile(o.cpu_seconds, 0.5);
    double sum = o.prepare_cpu_seconds;
    for (double c : o.cpu_seconds) sum += c;
    std::printf("%-8s %8.1f %8.1f %8.1f %10.1f %8.1f %9.3f %9.3f %9.3f %9.3f %9.1f\n", name.c_str(), 1e3 * p50,
                1e3 * percentile(o.cpu_seconds, 0.9), 1e3 * (p50 + grids), pcl_p50 / (p50 + grids),
                1e3 * percentile(o.seconds, 0.5), percentile(o.translation_m, 0.5), percentile(o.translation_m, 0.9),
                percentile(o.yaw_deg, 0.5), percentile(o.yaw_deg, 0.9), sum);
  }
  const auto serial = g_outcomes.find("pairs_in_parallel_1"), parallel = g_outcomes.find("pairs_in_parallel_2");
  if (serial != g_outcomes.end() && parallel != g_outcomes.end()) {
    std::printf("ours, pairs spread over 1 -> 2 threads (as the pipeline), wall clock of all pairs and grids: "
                "%.2f s -> %.2f s, %.2fx\n", serial->second.all_pairs_seconds, parallel->second.all_pairs_seconds,
                serial->second.all_pairs_seconds / parallel->second.all_pairs_seconds);
  }
  const auto one = g_outcomes.find("ours_1"), two = g_outcomes.find("ours_2");
  if (one != g_outcomes.end() && two != g_outcomes.end()) {
    double t1 = one->second.prepare_seconds, t2 = two->second.prepare_seconds;
    for (double s : one->second.seconds) t1 += s;
    for (double s : two->second.seconds) t2 += s;
    std::printf("ours 1 -> 2 threads, wall clock of all pairs and grids: %.2f s -> %.2f s, %.2fx\n", t1, t2, t1 / t2);
  }
  std::printf("(ms of CPU per pair; +grids: p50 plus the grids' share per pair; x PCL: PCL's p50 over that;\n"
              " t: error at the overlap's centroid, yaw in degrees, against the reference navigation)\n");
}

}  // namespace

int main(int argc, char** argv) {
  const std::filesystem::path bundle = bench::lake_bundle(argc, argv);
  const std::size_t max_pairs = take_max_pairs(argc, argv);
  benchmark::Initialize(&argc, argv);
  std::printf("load average before: %s\n", load().c_str());
  Input input = make_input(bundle, max_pairs);
  g_input = &input;
  std::size_t points = 0;
  for (const Cloud::Ptr& c : input.clouds) points += c->size();
  std::printf("%zu pairs of %s (%zu submaps, %zu filtered points per submap on average)\n", input.pairs.size(),
              bundle.c_str(), input.clouds.size(), points / std::max<std::size_t>(input.clouds.size(), 1));
  benchmark::RunSpecifiedBenchmarks();
  summary();
  std::printf("load average after: %s\n", load().c_str());
  return 0;
}
