// The scheduler's job flow against a real PostgreSQL: a stored survey and a queued job go in, and
// the job's results come out of the database as `process` makes them offline.
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <thread>

#include <sys/resource.h>
#include <unistd.h>

#include <csignal>

#include <gtest/gtest.h>

#include "core/io/bundle.h"
#include "core/pipeline/parameters.h"
#include "core/pipeline/pipeline.h"
#include "core/products/corrected_gsf.h"
#include "core/sim/simulator.h"
#include "server/scheduler/scheduler.h"
#include "tests/integration/fresh_database.h"

namespace bathyslam::server {
namespace {

namespace fs = std::filesystem;

struct SchedulerFixture {
  testing::FreshDatabase db;
  storage::ConnectionPool pool{db.conninfo(), 4};
  storage::SurveyStore surveys{pool};
  storage::JobQueue jobs{pool};
  storage::ResultStore results{pool};
  fs::path scratch = fs::temp_directory_path() / ("scheduler_test_" + db.name() + "_" + std::to_string(getpid()));

  SchedulerFixture() { fs::create_directories(scratch); }
  ~SchedulerFixture() { fs::remove_all(scratch); }

  // The small simulated survey as a bundle in the database, and the folder it was written to;
  // `change` may alter the survey first.
  std::int64_t stored_survey(const fs::path& bundle, const std::function<void(Survey&)>& change = [](Survey&) {}) {
    Survey survey = sim::simulate(sim::SimulationConfig{}).survey;
    change(survey);
    write_bundle(survey, bundle);
    std::vector<storage::FileUpload> files;
    for (const fs::directory_entry& entry : fs::directory_iterator(bundle)) {
      std::ifstream in(entry.path(), std::ios::binary);
      files.push_back({entry.path().filename().string(),
                       storage::Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>())});
    }
    return surveys.create_survey(surveys.create_tenant("acme"), "small", files);
  }

  SchedulerOptions options() const {
    SchedulerOptions o;
    o.name = "test";
    o.scratch = scratch;
    return o;
  }

  // Runs the scheduler until `job` has finished, one way or the other (or 5 minutes passed).
  storage::JobStatus run_until_finished(std::int64_t job) {
    Scheduler scheduler(surveys, jobs, results, options());
    scheduler.start();
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
    storage::JobStatus status = jobs.status(job);
    while ((status.state == storage::JobState::kQueued || status.state == storage::JobState::kRunning) &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      status = jobs.status(job);
    }
    scheduler.stop();
    return status;
  }
};

TEST(Scheduler, AQueuedJobIsRunAndItsResultsAreThoseOfTheSameRunOffline) {
  SchedulerFixture f;
  const fs::path bundle = f.scratch / "bundle";
  const std::int64_t survey = f.stored_survey(bundle);
  const PipelineConfig config = configuration_of("mchs", std::map<std::string, std::string>{});
  const std::int64_t job = f.jobs.enqueue({survey, "mchs", parameters(config)});

  const storage::JobStatus status = f.run_until_finished(job);
  ASSERT_EQ(status.state, storage::JobState::kSucceeded) << status.error.value_or("");

  const PipelineResult offline = run_pipeline(load_bundle(bundle), config);
  const std::vector<Eigen::Isometry3d> stored = f.results.load_optimized_poses(job);
  ASSERT_EQ(stored.size(), offline.optimized_poses.size());
  for (std::size_t i = 0; i < stored.size(); ++i) {
    EXPECT_LT((stored[i].translation() - offline.optimized_poses[i].translation()).norm(), 1e-6) << "submap " << i;
  }
  EXPECT_EQ(f.results.submap_poses(job).size(), offline.submaps.submaps.size());

  const std::optional<storage::Report> report = f.results.load_report(job);
  ASSERT_TRUE(report);
  EXPECT_EQ(report->report.at("configuration"), "mchs");
  EXPECT_LT(report->report.at("consistency_error_m").at("optimized").at("rmse").get<double>(),
            report->report.at("consistency_error_m").at("dead_reckoning").at("rmse").get<double>());
  EXPECT_FALSE(report->plots.empty());
  EXPECT_EQ(report->report.at("failed_products"), nlohmann::json::array());

  ASSERT_TRUE(f.results.map_grid(job));
  bool geotiff = false;
  for (const storage::TileKey& key : f.results.tiles(job)) geotiff |= key.format == "geotiff";
  EXPECT_TRUE(geotiff);
  EXPECT_GT(f.results.file_size(job, kCorrectedGsfFile).value_or(0), 0);

  // Watchers saw the stages go by, and the last word was "done".
  const std::vector<storage::JobEvent> events = f.jobs.events(job);
  ASSERT_FALSE(events.empty());
  bool registered = false;
  for (const storage::JobEvent& e : events) registered |= e.stage == "register";
  EXPECT_TRUE(registered);
  EXPECT_EQ(events.back().stage, "done");
}

TEST(Scheduler, AJobWhoseStoredParametersAreNotKnownFailsSayingWhichAndStoresNothing) {
  SchedulerFixture f;
  const std::int64_t survey = f.stored_survey(f.scratch / "bundle");
  const std::int64_t job = f.jobs.enqueue({survey, "mchs", {{"registration.gicp.no_such_knob", 1.0}}});

  const storage::JobStatus status = f.run_until_finished(job);
  ASSERT_EQ(status.state, storage::JobState::kFailed);
  EXPECT_EQ(status.attempts, 1) << "its own input's fault: not tried again";
  ASSERT_TRUE(status.error);
  EXPECT_NE(status.error->find("registration.gicp.no_such_knob"), std::string::npos) << *status.error;
  EXPECT_FALSE(f.results.load_report(job));
  EXPECT_TRUE(f.results.load_optimized_poses(job).empty());
  EXPECT_TRUE(f.results.tiles(job).empty());
}

// Cancels the job, as CancelJob does, from inside the store step that inserts into `table`:
// the cancel lands at a known point of the store, whatever the timing.
void cancel_when_stored_into(storage::ConnectionPool& pool, const std::string& table) {
  auto connection = pool.acquire();
  connection->exec(
      "CREATE FUNCTION cancel_the_job() RETURNS trigger LANGUAGE plpgsql AS $$ BEGIN"
      " UPDATE jobs SET state = 'cancelled', finished_at = now(), lease_expires_at = NULL WHERE id = NEW.job_id;"
      " RETURN NEW; END $$");
  connection->exec("CREATE TRIGGER cancel_the_job AFTER INSERT ON " + table +
                   " FOR EACH ROW EXECUTE FUNCTION cancel_the_job()");
}

// The job's rows in every table its results go to, and its origin.
long long stored_rows(testing::FreshDatabase& db, std::int64_t job) {
  const std::string id = std::to_string(job);
  long long rows = db.scalar("SELECT count(*) FROM jobs WHERE origin_easting IS NOT NULL AND id = " + id);
  for (const char* table : {"submaps", "constraints", "optimized_poses", "tiles", "maps", "job_files", "reports"})
    rows += db.scalar(std::string("SELECT count(*) FROM ") + table + " WHERE job_id = " + id);
  return rows;
}

bool stored_step(const std::vector<storage::JobEvent>& events, const std::string& step) {
  for (const storage::JobEvent& e : events)
    if (e.stage == "store" && e.message == step) return true;
  return false;
}

// Issue 37 fault 4: a cancel between two store steps left the steps before it stored and served.
TEST(Scheduler, AJobCancelledBetweenStoreStepsKeepsNothing) {
  SchedulerFixture f;
  const std::int64_t survey = f.stored_survey(f.scratch / "bundle");
  const std::int64_t job = f.jobs.enqueue({survey, "odometry", {}});
  cancel_when_stored_into(f.pool, "maps");  // the tiles step, after submaps, constraints and poses

  EXPECT_EQ(f.run_until_finished(job).state, storage::JobState::kCancelled);
  const std::vector<storage::JobEvent> events = f.jobs.events(job);
  EXPECT_TRUE(stored_step(events, "tiles"));
  EXPECT_FALSE(stored_step(events, "report")) << "the cancel came before the last step";
  EXPECT_EQ(stored_rows(f.db, job), 0);
}

// The same after the last step, before the job is marked succeeded.
TEST(Scheduler, AJobCancelledAfterItsLastStoreStepKeepsNothing) {
  SchedulerFixture f;
  const std::int64_t survey = f.stored_survey(f.scratch / "bundle");
  const std::int64_t job = f.jobs.enqueue({survey, "odometry", {}});
  cancel_when_stored_into(f.pool, "reports");

  EXPECT_EQ(f.run_until_finished(job).state, storage::JobState::kCancelled);
  EXPECT_TRUE(stored_step(f.jobs.events(job), "report"));
  EXPECT_EQ(stored_rows(f.db, job), 0);
}

// Issue 37 fault 2: a job whose scratch files the disk refuses is the server's trouble, not a
// verdict on its survey: given back to the queue (the attempt counts), and failed only once its
// attempts are used up, saying it was the disk. Files over 1000 bytes stand for a full disk; the
// bundle is read straight from the database, so the first file refused is the map's GeoTIFF,
// whose refusal GDAL says only in words.
TEST(Scheduler, AJobWhoseScratchDiskRefusesAWriteIsGivenBackNotFailedForItsInput) {
  SchedulerFixture f;
  const std::int64_t survey = f.stored_survey(f.scratch / "bundle");
  const std::int64_t job = f.jobs.enqueue({survey, "odometry", {}, 2});
  rlimit unlimited{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &unlimited), 0);
  signal(SIGXFSZ, SIG_IGN);  // a write past the limit fails with EFBIG instead of ending the process
  const rlimit small{1000, unlimited.rlim_max};
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  const storage::JobStatus status = f.run_until_finished(job);
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &unlimited), 0);

  EXPECT_EQ(status.state, storage::JobState::kFailed);
  EXPECT_EQ(status.attempts, 2) << "given back after the first";
  EXPECT_NE(status.error.value_or("").find("could not write its scratch files"), std::string::npos)
      << status.error.value_or("");
  EXPECT_EQ(stored_rows(f.db, job), 0);
}

// Issue 37 fault 6: a survey the corrected GSF cannot hold (a ping of more beams than its
// 2-byte field) failed the whole job after its map was made. The GSF is optional: the map is
// published, and the report says which product failed and why, without the scratch folder.
TEST(Scheduler, AFailedCorrectedGsfLeavesTheMapPublishedAndIsReported) {
  SchedulerFixture f;
  const std::int64_t survey = f.stored_survey(f.scratch / "bundle", [](Survey& s) {
    // The last ping (its beams the last of the array) grows to 40,000 beams, copies of its own.
    Ping& last = s.pings.back();
    ASSERT_EQ(last.first_beam + last.beam_count, s.beams.size());
    for (std::uint32_t k = last.beam_count; k < 40'000; ++k) {
      Beam beam = s.beams[last.first_beam + k % last.beam_count];
      beam.index = k;
      s.beams.push_back(beam);
    }
    last.beam_count = 40'000;
  });
  const std::int64_t job = f.jobs.enqueue({survey, "odometry", {}});

  const storage::JobStatus status = f.run_until_finished(job);
  ASSERT_EQ(status.state, storage::JobState::kSucceeded) << status.error.value_or("");
  EXPECT_TRUE(f.results.map_grid(job));
  EXPECT_FALSE(f.results.tiles(job).empty());
  EXPECT_EQ(f.results.file_size(job, kCorrectedGsfFile), std::nullopt);
  const std::optional<storage::Report> report = f.results.load_report(job);
  ASSERT_TRUE(report);
  const nlohmann::json& failed = report->report.at("failed_products");
  ASSERT_EQ(failed.size(), 1u) << failed;
  EXPECT_EQ(failed[0].at("product"), kCorrectedGsfFile);
  const std::string reason = failed[0].at("reason");
  EXPECT_NE(reason.find("number of beams"), std::string::npos) << reason;
  EXPECT_EQ(reason.find(f.scratch.string()), std::string::npos) << reason;
}

}  // namespace
}  // namespace bathyslam::server
