// The whole pipeline on the `small` simulated survey (6 lines, 46 submaps, about two seconds to
// simulate): each configuration against dead reckoning and the truth, its constraints by type and
// path, threads, cancellation, the corrected navigation and the report.
#include "core/pipeline/pipeline.h"

#include <gtest/gtest.h>

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <filesystem>
#include <mutex>
#include <set>
#include <thread>

#include "core/fuse/map_resolution.h"
#include "core/io/bundle.h"
#include "core/pipeline/job_input.h"
#include "core/pipeline/corrected_navigation.h"
#include "core/pipeline/streamed_survey.h"
#include "core/products/map_products.h"
#include "core/parallel/parallel_for.h"
#include "core/pipeline/report.h"
#include "core/sim/simulator.h"
#include "core/summary/survey_summary.h"

namespace bathyslam {
namespace {

const Survey& small_survey() {
  static const Survey survey = sim::simulate(sim::SimulationConfig{}).survey;
  return survey;
}

PipelineResult run(Configuration configuration, int threads = 0) {
  PipelineConfig config = preset_config(configuration);
  config.threads = threads;
  return run_pipeline(small_survey(), config);
}

double rmse(const std::vector<double>& errors) { return error_stats(errors).rmse; }

struct Counts {
  int odometry = 0, adjacent = 0, loop = 0;            // in the graph
  int candidates = 0, direct = 0, feature_aided = 0;   // registrations, by path
};

Counts count(const PipelineResult& r) {
  Counts n;
  for (const Constraint& c : r.constraints) {
    if (c.type != ConstraintType::kOdometry) {
      ++n.candidates;
      n.direct += c.path == RegistrationPath::kDirect;
      n.feature_aided += c.path == RegistrationPath::kFeatureAided;
    }
    if (!c.in_graph()) continue;
    n.odometry += c.type == ConstraintType::kOdometry;
    n.adjacent += c.type == ConstraintType::kAdjacent;
    n.loop += c.type == ConstraintType::kLoop;
  }
  return n;
}

// Horizontal RMS distance of a navigation to the survey's reference at the same samples.
double navigation_rmse(const std::vector<NavSample>& nav, const std::vector<NavSample>& reference) {
  double sum = 0;
  for (std::size_t i = 0; i < nav.size(); ++i) {
    sum += std::pow(nav[i].easting - reference[i].easting, 2) + std::pow(nav[i].northing - reference[i].northing, 2);
  }
  return std::sqrt(sum / static_cast<double>(nav.size()));
}

TEST(ParallelFor, CarriesAnIterationsExceptionOutOfTheLoop) {
  std::atomic<int> ran = 0;
  EXPECT_THROW(parallel_for(1000, 2, nullptr, [&](std::size_t i) {
                 ++ran;
                 std::this_thread::sleep_for(std::chrono::microseconds(100));  // a unit of work
                 if (i == 7) throw std::runtime_error("iteration 7");
               }),
               std::runtime_error);
  EXPECT_LT(ran.load(), 1000) << "the loop stops taking iterations after a failure";
}

TEST(ParallelFor, StopsWhenCancelledAndSaysSo) {
  std::atomic<bool> cancel = false;
  std::atomic<int> ran = 0;
  EXPECT_THROW(parallel_for(1000, 2, &cancel, [&](std::size_t i) {
                 ++ran;
                 std::this_thread::sleep_for(std::chrono::microseconds(100));
                 if (i == 3) cancel = true;
               }),
               Cancelled);
  EXPECT_LT(ran.load(), 1000);
}

TEST(ParallelFor, RunsOnTheThreadsItIsGiven) {
  for (int threads : {1, 2}) {
    std::mutex mutex;
    std::set<std::thread::id> seen;
    parallel_for(64, threads, nullptr, [&](std::size_t) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      const std::lock_guard lock(mutex);
      seen.insert(std::this_thread::get_id());
    });
    EXPECT_LE(static_cast<int>(seen.size()), threads);
    if (threads == 2) {
      EXPECT_EQ(seen.size(), 2u) << "64 iterations of 2 ms on 2 threads use both";
    }
  }
}

TEST(Pipeline, OdometryPublishesDeadReckoning) {
  const PipelineResult r = run(Configuration::kOdometry);
  const Counts n = count(r);
  ASSERT_GT(r.submaps.submaps.size(), 20u);
  EXPECT_EQ(n.odometry, static_cast<int>(r.submaps.submaps.size()) - 1);
  EXPECT_EQ(n.candidates, 0);
  for (std::size_t i = 0; i < r.dr_poses.size(); ++i) {
    EXPECT_LT((r.optimized_poses[i].translation() - r.dr_poses[i].translation()).norm(), 1e-6) << "submap " << i;
  }
  EXPECT_NEAR(rmse(r.trajectory_errors), rmse(r.dr_trajectory_errors), 1e-6);
  EXPECT_GT(rmse(r.dr_trajectory_errors), 1.0);  // the survey drifts: the tests below have something to remove
}

// The paper's baseline: adjacent survey lines registered directly from dead reckoning, no loops.
TEST(Pipeline, GicpRegistersAdjacentLinesDirectlyAndClosesNoLoops) {
  const PipelineResult r = run(Configuration::kGicp);
  const Counts n = count(r);
  EXPECT_GT(n.adjacent, 10);
  EXPECT_EQ(n.loop, 0);
  EXPECT_EQ(n.feature_aided, 0);
  EXPECT_EQ(n.direct, n.candidates);
  EXPECT_LT(r.consistency.stats.rmse, r.dr_consistency.stats.rmse);
}

// The first half of a job, as `process` and the scheduler both run it: the map's cell size from
// the soundings' density, and a map larger than the limit refused before any work, naming the
// navigation's extent.
TEST(JobInput, ChoosesTheMapCellsFromTheSoundingsAndRefusesATooLargeMapBeforeAnyWork) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "bathyslam_job_input";
  std::filesystem::remove_all(dir);
  write_bundle(small_survey(), dir);
  const PipelineConfig config = preset_config(Configuration::kMchs);
  const auto read = [&](PingSink& sink) {
    BundleReadResult r = stream_bundle(dir, sink);
    if (!r.survey) throw BundleError(std::move(r.problems));
    return std::move(*r.survey);
  };
  const JobInput input = read_job_input(read, config, FuseConfig{.resolution_m = 0});
  EXPECT_EQ(input.fuse.resolution_m, auto_map_resolution(small_survey(), FuseConfig{}.min_soundings));
  EXPECT_EQ(input.pings, small_survey().pings.size());
  EXPECT_EQ(input.submaps.submaps.size(), build_submaps(small_survey(), config.submaps).submaps.size());
  EXPECT_TRUE(input.survey.beams.empty()) << "the soundings are not held";

  const JobInput given = read_job_input(read, config, FuseConfig{.resolution_m = 2.0});
  EXPECT_EQ(given.fuse.resolution_m, 2.0) << "a cell size the caller chose stays";
  try {
    read_job_input(read, config, FuseConfig{.resolution_m = 0, .max_cells = 1000});
    ADD_FAILURE() << "a map of more than 1000 cells was not refused";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("nav.csv"), std::string::npos) << error.what();
  }
  std::filesystem::remove_all(dir);
}

// `bathyslam process` and the service's jobs stream a bundle's pings into the submaps (and what
// the map's cell size and extent need) without holding the soundings: the same result as from
// the survey held whole, and the "submaps" stage timed from when the caller began.
TEST(Pipeline, ABundleStreamedIntoSubmapsGivesTheSameResult) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "bathyslam_pipeline_streamed";
  std::filesystem::remove_all(dir);
  write_bundle(small_survey(), dir);
  const PipelineConfig config = preset_config(Configuration::kGicp);
  PipelineInputs inputs(config.submaps);
  const BundleReadResult read = stream_bundle(dir, inputs);
  std::filesystem::remove_all(dir);
  ASSERT_TRUE(read.survey);
  EXPECT_TRUE(read.survey->beams.empty());
  // What the map's cell size and extent need, as from the survey held whole.
  const SweptArea swept = inputs.outlines().swept_area(read.survey->nav), whole_swept = swept_area(small_survey());
  EXPECT_EQ(swept.soundings, whole_swept.soundings);
  EXPECT_EQ(swept.swath_m, whole_swept.swath_m);
  EXPECT_EQ(swept.track_m, whole_swept.track_m);
  EXPECT_EQ(inputs.outlines().sounding_reach_m(), sounding_reach_m(small_survey().beams));
  EXPECT_GT(inputs.outlines().sounding_reach_m(), 10.0);
  // And what a survey's summary counts (FinalizeSurvey summarizes a streamed upload).
  Survey outlined = *read.survey;
  outlined.pings = inputs.outlines().pings_without_beams();
  const SurveySummary summary = summarize(outlined), whole_summary = summarize(small_survey());
  EXPECT_EQ(summary.pings, whole_summary.pings);
  EXPECT_EQ(summary.soundings, whole_summary.soundings);
  EXPECT_EQ(summary.time_begin, whole_summary.time_begin);
  EXPECT_EQ(summary.time_end, whole_summary.time_end);

  const PipelineResult whole = run_pipeline(small_survey(), config);
  const PipelineResult streamed = run_pipeline(inputs.take_submaps(), 7.0, config);
  ASSERT_EQ(streamed.submaps.submaps.size(), whole.submaps.submaps.size());
  for (std::size_t i = 0; i < whole.submaps.submaps.size(); ++i) {
    const Submap& a = whole.submaps.submaps[i];
    const Submap& b = streamed.submaps.submaps[i];
    ASSERT_EQ(a.points.size(), b.points.size()) << "submap " << i;
    EXPECT_EQ(a.line, b.line);
    EXPECT_EQ(a.reference_pose.has_value(), b.reference_pose.has_value());
    // The bundle keeps every value exactly, so georeferencing gives the same floats.
    EXPECT_TRUE(a.points == b.points) << "submap " << i;
  }
  ASSERT_EQ(streamed.optimized_poses.size(), whole.optimized_poses.size());
  for (std::size_t i = 0; i < whole.optimized_poses.size(); ++i) {
    EXPECT_TRUE(streamed.optimized_poses[i].isApprox(whole.optimized_poses[i], 1e-12)) << "submap " << i;
  }
  EXPECT_EQ(corrected_navigation(*read.survey, streamed).size(), small_survey().nav.size());
  ASSERT_FALSE(streamed.timings.empty());
  EXPECT_EQ(streamed.timings.front().stage, "submaps");
  EXPECT_GE(streamed.timings.front().seconds, 7.0) << "the time the caller took to build them";
}

class MchsPipeline : public testing::Test {
 protected:
  static void SetUpTestSuite() { result_ = new PipelineResult(run(Configuration::kMchs)); }
  static void TearDownTestSuite() { delete result_; }
  static const PipelineResult& result() { return *result_; }

 private:
  static PipelineResult* result_;
};
PipelineResult* MchsPipeline::result_ = nullptr;

TEST_F(MchsPipeline, RemovesMostOfTheDriftWithLoopClosures) {
  const PipelineResult& r = result();
  const Counts n = count(r);
  EXPECT_GT(n.adjacent, 5);
  EXPECT_GT(n.loop, 2);  // the check lines cross the lawnmower
  EXPECT_GT(n.direct, 0);
  EXPECT_GT(n.feature_aided, 0);
  EXPECT_LT(rmse(r.trajectory_errors), 0.5 * rmse(r.dr_trajectory_errors));
  EXPECT_LT(r.consistency.stats.rmse, 0.5 * r.dr_consistency.stats.rmse);
  EXPECT_TRUE(r.safety_net.ran);
  EXPECT_TRUE(r.safety_net.pass);
  EXPECT_FALSE(r.safety_net.fell_back);
}

TEST_F(MchsPipeline, RejectionsSayWhy) {
  for (const Constraint& c : result().constraints) {
    if (c.type == ConstraintType::kOdometry) continue;
    if (!c.accepted()) {
      EXPECT_NE(c.rejection.kind, RejectionKind::kNone) << c.from << "-" << c.to;
      EXPECT_FALSE(c.rejection.detail.empty()) << c.from << "-" << c.to;
    } else {
      EXPECT_EQ(c.rejection.kind, RejectionKind::kNone) << c.from << "-" << c.to;
    }
  }
}

TEST_F(MchsPipeline, CorrectedNavigationFollowsTheOptimizedSubmaps) {
  const Survey& survey = small_survey();
  const std::vector<NavSample> corrected = corrected_navigation(survey, result());
  ASSERT_EQ(corrected.size(), survey.nav.size());
  for (std::size_t i = 0; i < corrected.size(); i += 97) EXPECT_EQ(corrected[i].time, survey.nav[i].time);
  ASSERT_TRUE(survey.reference_nav);
  ASSERT_EQ(survey.reference_nav->size(), survey.nav.size());
  const double before = navigation_rmse(survey.nav, *survey.reference_nav);
  const double after = navigation_rmse(corrected, *survey.reference_nav);
  EXPECT_LT(after, 0.5 * before) << "dead reckoning " << before << " m, corrected " << after << " m";
}

TEST_F(MchsPipeline, ReportCarriesTheResult) {
  const PipelineResult& r = result();
  const nlohmann::json j = report_json(r);
  const Counts n = count(r);
  EXPECT_EQ(j.at("configuration"), "mchs");
  EXPECT_DOUBLE_EQ(j.at("trajectory_error_m").at("optimized").at("rmse").get<double>(), rmse(r.trajectory_errors));
  EXPECT_DOUBLE_EQ(j.at("consistency_error_m").at("optimized").at("rmse").get<double>(), r.consistency.stats.rmse);
  EXPECT_EQ(j.at("constraints").at("by_type").at("loop").at("accepted").get<int>(), n.loop);
  EXPECT_EQ(j.at("registrations").size(), static_cast<std::size_t>(n.candidates));
  EXPECT_EQ(j.at("safety_net").at("pass").get<bool>(), r.safety_net.pass);
  // The stored parameters describe the run: set into a fresh configuration they give it back.
  PipelineConfig again;
  for (const auto& [name, value] : j.at("parameters").items()) set_parameter(again, name, value.get<double>());
  EXPECT_EQ(parameters(again), parameters(r.config));
}

// The service stores report.json and answers GetReport from it: the summary read back is the
// one written, and a report missing a key is refused by name, not read as zeros.
TEST_F(MchsPipeline, ReportSummaryReadsBackFromItsJsonExactly) {
  const PipelineResult& r = result();
  const ReportSummary written = report_summary(r);
  nlohmann::json j = report_json(r);
  const ReportSummary read = report_summary_from_json(j);
  EXPECT_EQ(read.configuration, written.configuration);
  using Pair = std::pair<ErrorStats, ErrorStats>;
  for (const auto& [a, b] : {Pair{read.trajectory, written.trajectory}, Pair{read.trajectory_dr, written.trajectory_dr},
                             Pair{read.consistency, written.consistency}, Pair{read.consistency_dr, written.consistency_dr}}) {
    EXPECT_DOUBLE_EQ(a.rmse, b.rmse);
    EXPECT_DOUBLE_EQ(a.p99, b.p99);
    EXPECT_DOUBLE_EQ(a.max, b.max);
    EXPECT_EQ(a.count, b.count);
  }
  EXPECT_DOUBLE_EQ(read.histogram.bin_width, written.histogram.bin_width);
  EXPECT_EQ(read.histogram.counts, written.histogram.counts);
  for (const auto& [name, counts] : written.by_type) {
    EXPECT_EQ(read.by_type.at(name).accepted, counts.accepted) << name;
    EXPECT_EQ(read.by_type.at(name).rejections, counts.rejections) << name;
  }
  EXPECT_EQ(read.by_path.size(), written.by_path.size());

  j.at("consistency_error_m").erase("dead_reckoning");
  try {
    report_summary_from_json(j);
    FAIL() << "a report without the dead-reckoning consistency must not be read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("dead_reckoning"), std::string::npos) << e.what();
  }
}

// What `process` and a job hand over as the map: the COG that GDAL reads with the run's grid and
// CRS, the BAG, a .tif, .vdb and .png per tile, the plots; nothing at all when no cell has
// enough soundings.
TEST_F(MchsPipeline, MapProductsAreWrittenAsGdalReadsThem) {
  const PipelineResult& r = result();
  const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / "map_products";
  std::filesystem::remove_all(dir);
  const MapFiles files = write_map_products(r, small_survey().metadata, FuseConfig{}, dir);
  ASSERT_TRUE(files.written);
  GDALAllRegister();
  const std::unique_ptr<GDALDataset> map(GDALDataset::Open((dir / "map.tif").c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  ASSERT_NE(map, nullptr);
  EXPECT_EQ(map->GetRasterXSize(), files.geometry.width);
  EXPECT_EQ(map->GetRasterYSize(), files.geometry.height);
  const OGRSpatialReference* crs = map->GetSpatialRef();
  ASSERT_NE(crs, nullptr);
  OGRSpatialReference survey_crs;
  survey_crs.SetFromUserInput(small_survey().metadata.crs.c_str());
  EXPECT_TRUE(crs->IsSame(&survey_crs));
  EXPECT_TRUE(std::filesystem::exists(dir / "map.bag"));
  ASSERT_FALSE(files.tile_ids.empty());
  for (const TileId& id : files.tile_ids) {
    for (const char* extension : {".tif", ".vdb", ".png"}) {
      EXPECT_TRUE(std::filesystem::exists(dir / "tiles" / (tile_stem(id).string() + extension))) << tile_stem(id) << extension;
    }
  }
  EXPECT_EQ(files.plots, (std::vector<std::string>{"map.png", "map_difference.png"})) << "mchs moved the map";
  for (const std::string& plot : files.plots) EXPECT_TRUE(std::filesystem::exists(dir / plot)) << plot;

  FuseConfig sparse;
  sparse.min_soundings = 1 << 30;
  const std::filesystem::path empty = dir / "empty";
  EXPECT_FALSE(write_map_products(r, small_survey().metadata, sparse, empty).written);
  EXPECT_FALSE(std::filesystem::exists(empty));
}

// Issue 31 on a seabed `lake`'s mounds do not make: patches of sand waves, boulders, a channel, a
// slope break and flat mud, under a heading random walk. Loops without features close by the
// direct path, direct edges carry what their overlap observes, the noise comes from the survey;
// the map must gain what the plain `gicp` baseline gains and stay within its own information.
class MixedSeabed : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    sim::SimulationConfig simulation;
    simulation.terrain.kind = sim::TerrainKind::kMixed;
    simulation.drift = sim::DriftModel::kHeadingWalk;
    survey_ = new Survey(sim::simulate(simulation).survey);
    for (Configuration c : {Configuration::kOdometry, Configuration::kGicp, Configuration::kMchs}) {
      results_[static_cast<int>(c)] = new PipelineResult(run_pipeline(*survey_, preset_config(c)));
    }
  }
  static void TearDownTestSuite() {
    for (PipelineResult*& r : results_) delete r, r = nullptr;
    delete survey_;
  }
  static const PipelineResult& result(Configuration c) { return *results_[static_cast<int>(c)]; }
  static const Survey& survey() { return *survey_; }

 private:
  static Survey* survey_;
  static PipelineResult* results_[3];
};
Survey* MixedSeabed::survey_ = nullptr;
PipelineResult* MixedSeabed::results_[3] = {};

TEST_F(MixedSeabed, MchsMakesTheMapAsConsistentAsGicpDoesAndTheTrajectoryNoWorse) {
  const PipelineResult &odometry = result(Configuration::kOdometry), &gicp = result(Configuration::kGicp),
                       &mchs = result(Configuration::kMchs);
  EXPECT_FALSE(mchs.safety_net.fell_back) << mchs.safety_net.verdict;
  EXPECT_LE(mchs.consistency.stats.rmse, 1.05 * gicp.consistency.stats.rmse);
  EXPECT_LT(mchs.consistency.stats.rmse, 0.5 * odometry.consistency.stats.rmse);
  EXPECT_LE(rmse(mchs.trajectory_errors), 1.05 * rmse(odometry.trajectory_errors));
  EXPECT_TRUE(mchs.navigation_noise.estimated);
}

TEST_F(MixedSeabed, EveryAcceptedEdgeLiesWithinSixSigmaOfItsInformation) {
  const PipelineResult& mchs = result(Configuration::kMchs);
  int direct_loops = 0;
  for (const Constraint& c : mchs.constraints) {
    if (c.type == ConstraintType::kOdometry || !c.in_graph()) continue;
    direct_loops += c.type == ConstraintType::kLoop && c.path == RegistrationPath::kDirect;
    const auto sigmas = edge_error_sigmas(mchs.submaps, c.from, c.to, c.measured, c.anchor, c.information);
    ASSERT_TRUE(sigmas);
    EXPECT_LT(sigmas->joint, 6.0) << to_string(c.type) << " " << c.from << "->" << c.to;
  }
  EXPECT_GT(direct_loops, 0) << "featureless loops close by the direct path";
}

TEST_F(MixedSeabed, WithoutDirectLoopsNoFeaturelessLoopCloses) {
  PipelineConfig config = preset_config(Configuration::kMchs);
  config.direct_loops.enabled = false;
  const PipelineResult r = run_pipeline(survey(), config);
  for (const Constraint& c : r.constraints) {
    if (c.type == ConstraintType::kLoop && c.path == RegistrationPath::kDirect) {
      EXPECT_FALSE(c.accepted()) << c.from << "->" << c.to;
      EXPECT_EQ(c.rejection.kind, RejectionKind::kLoopWithoutFeatures);
    }
  }
}

// A flat plain cut by a meandering channel, under heading drift: no adjacent answer is unique
// (the channel fits anywhere along itself, the plain anywhere), so only the loops' positions
// across the channel can correct the survey, and dead reckoning's Table 1 prior puts every loop's
// guess beyond GICP's 3 m gate. Widened along the channel, with no reach test on the prior, the
// loops make the map several times more consistent (docs/slam-every-seabed.md). The widening
// is tested alone (no restarts in a better basin); with them, as by default, one more loop is
// placed, correctly, and the survey's noise estimate then trades heading for position noise
// (docs/slam-every-seabed.md, "Direct answers started again"): the map stays far better than
// dead reckoning's, the trajectory less so.
TEST(ChannelSeabed, LoopsAcrossTheChannelCorrectTheSurveyAndNoEdgeIsConfidentlyWrong) {
  sim::SimulationConfig simulation;
  simulation.terrain.kind = sim::TerrainKind::kChannel;
  simulation.drift = sim::DriftModel::kHeadingWalk;
  const Survey survey = sim::simulate(simulation).survey;
  const PipelineResult odometry = run_pipeline(survey, preset_config(Configuration::kOdometry));
  PipelineConfig widening_alone = preset_config(Configuration::kMchs);
  widening_alone.registration.best_basin_restarts = 0;
  const PipelineResult by_default = run_pipeline(survey, preset_config(Configuration::kMchs));
  EXPECT_FALSE(by_default.safety_net.fell_back) << by_default.safety_net.verdict;
  EXPECT_LT(by_default.consistency.stats.rmse, 0.5 * odometry.consistency.stats.rmse);
  EXPECT_LT(rmse(by_default.trajectory_errors), 0.7 * rmse(odometry.trajectory_errors));
  const PipelineResult mchs = run_pipeline(survey, widening_alone);
  EXPECT_FALSE(mchs.safety_net.fell_back) << mchs.safety_net.verdict;
  EXPECT_LT(mchs.consistency.stats.rmse, 0.5 * odometry.consistency.stats.rmse);
  EXPECT_LT(rmse(mchs.trajectory_errors), 0.5 * rmse(odometry.trajectory_errors));
  for (const PipelineResult* r : {&mchs, &by_default}) {
    int placed_loops = 0;
    for (const Constraint& c : r->constraints) {
      if (c.type == ConstraintType::kOdometry || !c.in_graph()) continue;
      placed_loops += c.type == ConstraintType::kLoop && carries_horizontal_information(c.information);
      const auto sigmas = edge_error_sigmas(r->submaps, c.from, c.to, c.measured, c.anchor, c.information);
      ASSERT_TRUE(sigmas);
      EXPECT_LT(sigmas->joint, 6.0) << to_string(c.type) << " " << c.from << "->" << c.to;
    }
    EXPECT_GE(placed_loops, 3) << "loop closures with a horizontal position";
  }
}

TEST(Pipeline, OneAndTwoThreadsGiveTheSameResult) {
  const PipelineResult one = run(Configuration::kMchs, 1), two = run(Configuration::kMchs, 2);
  ASSERT_EQ(one.constraints.size(), two.constraints.size());
  for (std::size_t k = 0; k < one.constraints.size(); ++k) {
    const Constraint &a = one.constraints[k], &b = two.constraints[k];
    ASSERT_EQ(a.from, b.from);
    ASSERT_EQ(a.to, b.to);
    EXPECT_EQ(a.in_graph(), b.in_graph()) << a.from << "-" << a.to;
    EXPECT_LT((a.measured.translation() - b.measured.translation()).norm(), 1e-9) << a.from << "-" << a.to;
  }
  for (std::size_t i = 0; i < one.optimized_poses.size(); ++i) {
    EXPECT_LT((one.optimized_poses[i].translation() - two.optimized_poses[i].translation()).norm(), 1e-9);
  }
}

// A job stopped in its register stage and run again (docs/service.md, "Jobs that resume"): the
// second run takes up the batches the first stored, registers the rest, and ends exactly where
// an uninterrupted run does, every registration's record and every pose the same.
nlohmann::json without_times(nlohmann::json report) {
  report.erase("timings_s");
  report.at("graph").erase("batch_solve_s");
  for (auto& [key, value] : report.at("graph").items()) {
    if (key.size() > 2 && key.ends_with("_s")) value = nullptr;
  }
  return report;
}

TEST(Pipeline, AResumedRunTakesUpTheStoredBatchesAndEndsAsTheUninterruptedOne) {
  const PipelineConfig config = preset_config(Configuration::kMchs);
  const SubmapSet submaps = build_submaps(small_survey(), config.submaps);
  std::vector<RegisteredBatch> kept;
  RegistrationCheckpoints first{{}, [&](const RegisteredBatch& b) { kept.push_back(b); }};
  const PipelineResult whole = run_pipeline(submaps, 0, config, {}, nullptr, &first);
  ASSERT_GT(whole.batches, 2);
  ASSERT_EQ(kept.size(), static_cast<std::size_t>(whole.batches));
  EXPECT_EQ(whole.batches_taken_up, 0);

  // The first half as the stopped run stored it, through its bytes.
  RegistrationCheckpoints again;
  const std::size_t stored = kept.size() / 2;
  for (std::size_t k = 0; k < stored; ++k) again.stored.push_back(batch_from_checkpoint(checkpoint_bytes(kept[k])));
  std::vector<RegisteredBatch> registered_again;
  again.keep = [&](const RegisteredBatch& b) { registered_again.push_back(b); };
  const PipelineResult resumed = run_pipeline(submaps, 0, config, {}, nullptr, &again);
  EXPECT_EQ(resumed.batches_taken_up, static_cast<int>(stored));
  ASSERT_EQ(registered_again.size(), kept.size() - stored);
  EXPECT_EQ(registered_again.front().begin, kept[stored].begin);
  ASSERT_EQ(resumed.optimized_poses.size(), whole.optimized_poses.size());
  for (std::size_t i = 0; i < whole.optimized_poses.size(); ++i) {
    EXPECT_TRUE(resumed.optimized_poses[i].matrix() == whole.optimized_poses[i].matrix()) << "submap " << i;
  }
  EXPECT_EQ(without_times(report_json(resumed)), without_times(report_json(whole)));

  // A batch of other pairs (the survey's submaps cut otherwise, another configuration), or of
  // the same pairs from other guesses (another solver's estimate), is not taken up: registered again.
  RegistrationCheckpoints other;
  other.stored = {kept.front(), kept[1]};
  other.stored[0].constraints.front().to += 1;
  other.stored[1].constraints.back().guess.translation().x() += 1e-9;
  EXPECT_EQ(run_pipeline(submaps, 0, config, {}, nullptr, &other).batches_taken_up, 0);
}

TEST(RegistrationCheckpoint, RefusesBytesThatAreNotABatchOfThisBuild) {
  RegisteredBatch batch{3, 7, {}};
  Constraint c;
  c.type = ConstraintType::kLoop;
  c.path = RegistrationPath::kDirect;
  c.horizontal_doubt = "from 1.5 m aside GICP lands 0.80 m away";
  c.uniqueness.reach = 1;
  c.uniqueness.competitors = {true, false, true, false, false, false, true, true, false};
  c.rejection = {RejectionKind::kImplausible, "Mahalanobis2 78.0 > 11.3"};
  batch.constraints = {c, c};
  const std::vector<std::uint8_t> bytes = checkpoint_bytes(batch);
  const RegisteredBatch back = batch_from_checkpoint(bytes);
  EXPECT_EQ(back.begin, 3);
  EXPECT_EQ(back.end, 7);
  ASSERT_EQ(back.constraints.size(), 2u);
  EXPECT_EQ(back.constraints[1].uniqueness.competitors, c.uniqueness.competitors);
  EXPECT_EQ(back.constraints[1].horizontal_doubt, c.horizontal_doubt);
  EXPECT_EQ(back.constraints[1].rejection.text(), c.rejection.text());
  EXPECT_EQ(checkpoint_bytes(back), bytes);

  std::vector<std::uint8_t> cut(bytes.begin(), bytes.end() - 1), longer = bytes, other_version = bytes;
  longer.push_back(0);
  other_version[4] ^= 1;
  for (const auto& wrong : {cut, longer, other_version, std::vector<std::uint8_t>{}}) {
    EXPECT_THROW(batch_from_checkpoint(wrong), CheckpointError);
  }
  // A mask that does not fit its reach would send competitor_offsets past its end; a reach whose
  // square's side overflows an int, even without a mask.
  batch.constraints[0].uniqueness.reach = 2;
  EXPECT_THROW(batch_from_checkpoint(checkpoint_bytes(batch)), CheckpointError);
  batch.constraints[0].uniqueness = {};
  batch.constraints[0].uniqueness.reach = 1 << 30;
  EXPECT_THROW(batch_from_checkpoint(checkpoint_bytes(batch)), CheckpointError);
}

TEST(Pipeline, CancellationStopsItDuringRegistration) {
  std::atomic<bool> cancel = false;
  std::vector<std::string> stages;
  const PipelineConfig config = preset_config(Configuration::kMchs);
  auto progress = [&](std::string_view stage, double) {
    if (stages.empty() || stages.back() != stage) stages.emplace_back(stage);
    if (stage == "register") cancel = true;
  };
  EXPECT_THROW(run_pipeline(small_survey(), config, progress, &cancel), Cancelled);
  EXPECT_EQ(stages.back(), "register");
}

// The same survey in a world four times larger (positions, depths and soundings, as if flown four
// times higher over a seabed four times larger) is the same problem in other units: its lengths
// scale by the measured footprint, and mchs decides as it does at the lake's scale. Compared in
// the map's shape (aligned trajectory) and consistency: the survey's overall turn, which no
// registration observes, lands differently at either scale (0.175 and 0.248 m unaligned, /4,
// with 0.141 and 0.132 m aligned on 2026-12-05).
TEST(Footprint, MchsDecidesAtFourTimesTheScaleAsAtTheLakes) {
  Survey larger = small_survey();
  const NavSample first = larger.nav.front();
  auto scaled = [&](std::vector<NavSample>& nav) {
    for (NavSample& n : nav) {
      n.easting = first.easting + 4 * (n.easting - first.easting);
      n.northing = first.northing + 4 * (n.northing - first.northing);
      n.depth_m *= 4;
    }
  };
  scaled(larger.nav);
  scaled(*larger.reference_nav);
  for (Beam& b : larger.beams) {
    b.along *= 4;
    b.across *= 4;
    b.down *= 4;
  }
  const PipelineResult lake = run(Configuration::kMchs);
  const PipelineResult r = run_pipeline(larger, preset_config(Configuration::kMchs));
  EXPECT_EQ(r.footprint_scale, 4);
  EXPECT_DOUBLE_EQ(r.config.grid.cell_m, 2.0);
  const Counts at_lake = count(lake), at_four = count(r);
  EXPECT_NEAR(at_four.adjacent + at_four.loop, at_lake.adjacent + at_lake.loop, 0.1 * (at_lake.adjacent + at_lake.loop));
  EXPECT_NEAR(rmse(r.aligned_trajectory_errors) / 4, rmse(lake.aligned_trajectory_errors),
              0.25 * rmse(lake.aligned_trajectory_errors));
  EXPECT_NEAR(r.consistency.stats.rmse / 4, lake.consistency.stats.rmse, 0.25 * lake.consistency.stats.rmse);
  EXPECT_LT(rmse(r.trajectory_errors), 0.5 * rmse(r.dr_trajectory_errors));
  EXPECT_FALSE(r.safety_net.fell_back);
}

// A survey without reference navigation, and one whose lines never overlap, has no trajectory
// error or no consistency error: the report says so and why, rather than zeros a user would read
// as a perfect result.
TEST(Report, SaysWhatWasNotComputedAndWhy) {
  Survey survey = small_survey();
  survey.reference_nav.reset();
  // The first 400 pings: the run-in and part of the first line, which nothing overlaps.
  survey.pings.resize(400);
  survey.beams.resize(survey.pings.back().first_beam + survey.pings.back().beam_count);
  const PipelineResult r = run_pipeline(survey, preset_config(Configuration::kOdometry));

  const nlohmann::json j = report_json(r);
  const nlohmann::json& trajectory = j.at("trajectory_error_m");
  EXPECT_TRUE(trajectory.at("optimized").is_null());
  EXPECT_TRUE(trajectory.at("dead_reckoning").is_null());
  EXPECT_EQ(trajectory.at("not_computed"), "no reference navigation");
  const nlohmann::json& consistency = j.at("consistency_error_m");
  EXPECT_TRUE(consistency.at("optimized").is_null());
  EXPECT_NE(consistency.at("not_computed").get<std::string>().find("no map cell seen by two survey lines"), std::string::npos);
  EXPECT_EQ(report_summary_from_json(j).trajectory.count, 0u);  // read back as nothing, not refused

  const std::string text = report_text(r);
  EXPECT_NE(text.find("trajectory error   not computed: no reference navigation"), std::string::npos) << text;
  EXPECT_NE(text.find("consistency error  not computed: no map cell seen by two survey lines"), std::string::npos) << text;
  EXPECT_EQ(text.find("rmse 0.00"), std::string::npos) << text;
}

}  // namespace
}  // namespace bathyslam
