// Job results round-trip, and a survey's deletion takes everything under it.
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include <unistd.h>
#include <zlib.h>

#include <gtest/gtest.h>

#include "server/storage/job_queue.h"
#include "server/storage/result_store.h"
#include "server/storage/survey_store.h"
#include "tests/integration/fresh_database.h"

namespace bathyslam::storage {
namespace {

Eigen::Isometry3d a_pose(double yaw, double x, double y, double z) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitX()) *
                   Eigen::AngleAxisd(-0.01, Eigen::Vector3d::UnitY()))
                      .toRotationMatrix();
  pose.translation() = Eigen::Vector3d(x, y, z);
  return pose;
}

// `smooth`: a gently sloping seafloor on a regular grid, which deflates well; otherwise noise.
Submap a_submap(int index, bool smooth) {
  Submap s;
  s.index = index;
  s.line = index == 1 ? -1 : 2;
  s.time_begin = 1.7e9 + index * 10.123456789;
  s.time_mid = s.time_begin + 5.0000001;
  s.time_end = s.time_begin + 9.99;
  s.dr_pose = a_pose(0.3 + index, 120.5 + 40 * index, -75.25, -10.125);
  if (index == 0) s.reference_pose = a_pose(0.31, 121.0, -75.0, -10.0);
  std::mt19937 random(index);
  std::normal_distribution<float> noise(0, 5);
  for (int i = 0; i < 2000; ++i) {
    if (smooth) s.points.emplace_back(static_cast<float>(i % 50), static_cast<float>(i / 50), -10.0f);
    else s.points.emplace_back(noise(random), noise(random), noise(random) - 10);
  }
  return s;
}

struct JobFixture {
  testing::FreshDatabase db;
  ConnectionPool pool{db.conninfo(), 2};
  SurveyStore surveys{pool};
  JobQueue jobs{pool};
  ResultStore results{pool};
  std::int64_t survey = surveys.create_survey(surveys.create_tenant("acme"), "lake", {{"nav.csv", {1, 2, 3}}});
  std::int64_t job = jobs.enqueue({survey, "gicp"});
};

void expect_same_pose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  // Through a quaternion the rotation comes back to within rounding, the translation exactly.
  EXPECT_TRUE(a.linear().isApprox(b.linear(), 1e-15)) << a.linear() << "\nvs\n" << b.linear();
  EXPECT_EQ(a.translation(), b.translation());
}

TEST(ResultStore, SubmapsRoundTripEveryField) {
  JobFixture f;
  const std::vector<Submap> saved = {a_submap(0, false), a_submap(1, true), a_submap(2, false)};
  f.results.save_submaps(f.job, saved);
  EXPECT_EQ(f.db.scalar("SELECT count(*) FROM submaps WHERE points_encoding = 'f32le-planes'"), 3);
  // Rows stored before the byte planes (migration 0014) are still read: submap 1 as plain
  // floats, submap 2 deflated.
  Bytes floats(saved[1].points.size() * 12), deflated(compressBound(saved[2].points.size() * 12));
  std::memcpy(floats.data(), saved[1].points.data(), floats.size());
  uLongf deflated_size = deflated.size();
  ASSERT_EQ(compress2(deflated.data(), &deflated_size, reinterpret_cast<const Bytef*>(saved[2].points.data()),
                      saved[2].points.size() * 12, Z_BEST_SPEED), Z_OK);
  deflated.resize(deflated_size);
  auto update = f.pool.acquire();
  update->exec("UPDATE submaps SET points_encoding = 'f32le', points = $2 WHERE job_id = $1 AND idx = 1", {f.job, floats});
  update->exec("UPDATE submaps SET points_encoding = 'f32le+zlib', points = $2 WHERE job_id = $1 AND idx = 2",
               {f.job, deflated});
  std::vector<Submap> loaded = f.results.load_submaps(f.job);
  ASSERT_EQ(loaded.size(), saved.size());
  for (std::size_t i = 0; i < saved.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(loaded[i].index, saved[i].index);
    EXPECT_EQ(loaded[i].line, saved[i].line);
    EXPECT_EQ(loaded[i].time_begin, saved[i].time_begin);
    EXPECT_EQ(loaded[i].time_mid, saved[i].time_mid);
    EXPECT_EQ(loaded[i].time_end, saved[i].time_end);
    expect_same_pose(loaded[i].dr_pose, saved[i].dr_pose);
    ASSERT_EQ(loaded[i].reference_pose.has_value(), saved[i].reference_pose.has_value());
    if (saved[i].reference_pose) expect_same_pose(*loaded[i].reference_pose, *saved[i].reference_pose);
    EXPECT_EQ(loaded[i].points, saved[i].points);
  }
  // A second save of the same submaps changes nothing and says why.
  EXPECT_THROW(f.results.save_submaps(f.job, {a_submap(5, true), a_submap(0, true)}), DatabaseError);
  EXPECT_EQ(f.db.scalar("SELECT count(*) FROM submaps"), 3);
}

TEST(ResultStore, FootprintsAnswerTheTilingLookup) {
  JobFixture f;
  f.results.save_submaps(f.job, {a_submap(0, false), a_submap(1, false), a_submap(2, false)});
  // Submap 2 sits around (200.5, -75.25), the others 40 and 80 m west of it.
  EXPECT_EQ(f.results.submaps_overlapping(f.job, Eigen::AlignedBox2d(Eigen::Vector2d(195, -80), Eigen::Vector2d(205, -70))),
            std::vector<int>{2});
  EXPECT_EQ(f.results.submaps_overlapping(f.job, Eigen::AlignedBox2d(Eigen::Vector2d(0, 0), Eigen::Vector2d(10, 10))),
            std::vector<int>{});
  EXPECT_EQ(f.results.submaps_overlapping(f.job, Eigen::AlignedBox2d(Eigen::Vector2d(100, -100), Eigen::Vector2d(220, 0))),
            (std::vector<int>{0, 1, 2}));
}

TEST(ResultStore, ConstraintsRoundTripEveryField) {
  JobFixture f;
  f.results.save_submaps(f.job, {a_submap(0, false), a_submap(1, false), a_submap(2, false)});
  Constraint odometry;
  odometry.type = ConstraintType::kOdometry;
  odometry.from = 0;
  odometry.to = 1;
  odometry.measured = a_pose(0.01, 40.0, 0.125, -0.5);
  Constraint registration;
  Constraint& c = registration;
  c.path = RegistrationPath::kFeatureAided;
  c.type = ConstraintType::kAdjacent;
  c.from = 0;
  c.to = 2;
  c.measured = a_pose(-0.2, 80.25, 1.0 / 3.0, 0.1);
  for (int r = 0; r < 6; ++r)
    for (int k = 0; k < 6; ++k) c.information(r, k) = r == k ? 100.0 / (r + 1) : 0.01 * (r + 1) * (k + 2);
  c.quality = {true, 0.123456789, 1234, 0.0625};
  c.overlap_fraction = 0.37;
  c.rejection = {RejectionKind::kOverlapMse, "6.1 m² > 5 m²"};
  c.guess = a_pose(0.05, 79.0, 0.5, 0.2);
  c.anchor = Eigen::Vector3d(1.0 / 3.0, -14.75, 10.125);
  c.path_reason = "feature density 0.0210 >= 0.0050, 46 matches";
  c.feature_density = 0.021;
  c.matches = 46;
  c.inlier_ratio = 0.8125;
  Constraint left_out = registration;  // accepted, then dropped by the back end
  left_out.rejection = {};
  left_out.exclusion = {RejectionKind::kSafetyNet, "pulled 7.2 sigma against the solution"};
  f.results.save_constraints(f.job, {odometry, registration, left_out});

  std::vector<Constraint> loaded = f.results.load_constraints(f.job);
  ASSERT_EQ(loaded.size(), 3u);
  EXPECT_EQ(loaded[0].path, std::nullopt);
  EXPECT_EQ(loaded[0].type, ConstraintType::kOdometry);
  EXPECT_EQ(loaded[0].information, Information6::Identity());
  EXPECT_TRUE(loaded[0].in_graph());
  const Constraint& l = loaded[1];
  EXPECT_EQ(l.path, c.path);
  EXPECT_EQ(l.type, c.type);
  EXPECT_EQ(l.from, c.from);
  EXPECT_EQ(l.to, c.to);
  expect_same_pose(l.measured, c.measured);
  EXPECT_EQ(l.information, c.information);  // exactly, and not transposed
  EXPECT_EQ(l.quality.converged, c.quality.converged);
  EXPECT_EQ(l.quality.fitness, c.quality.fitness);
  EXPECT_EQ(l.quality.overlap_points, c.quality.overlap_points);
  EXPECT_EQ(l.quality.overlap_mse_m2, c.quality.overlap_mse_m2);
  EXPECT_EQ(l.overlap_fraction, c.overlap_fraction);
  EXPECT_EQ(l.rejection.kind, c.rejection.kind);
  EXPECT_EQ(l.rejection.detail, c.rejection.detail);
  EXPECT_FALSE(l.accepted());
  expect_same_pose(l.guess, c.guess);
  EXPECT_TRUE(loaded[2].accepted());
  EXPECT_FALSE(loaded[2].in_graph());
  EXPECT_EQ(loaded[2].exclusion.kind, RejectionKind::kSafetyNet);
  EXPECT_EQ(loaded[2].exclusion.detail, left_out.exclusion.detail);
  EXPECT_EQ(l.anchor, c.anchor);
  EXPECT_EQ(l.path_reason, c.path_reason);
  EXPECT_EQ(l.feature_density, c.feature_density);
  EXPECT_EQ(l.matches, c.matches);
  EXPECT_EQ(l.inlier_ratio, c.inlier_ratio);

  // A constraint to a submap the job does not have, or without its path, changes nothing.
  Constraint dangling = registration;
  dangling.to = 7;
  EXPECT_THROW(f.results.save_constraints(f.job, {dangling}), DatabaseError);
  Constraint pathless = registration;
  pathless.path.reset();
  EXPECT_THROW(f.results.save_constraints(f.job, {pathless}), std::invalid_argument);
  EXPECT_EQ(f.results.load_constraints(f.job).size(), 3u);
}

TEST(ResultStore, PosesTilesAndReportsRoundTrip) {
  JobFixture f;
  f.results.save_submaps(f.job, {a_submap(0, false), a_submap(1, false)});
  const std::vector<Eigen::Isometry3d> poses = {a_pose(0.1, 1, 2, 3), a_pose(-3.0, -4, 5.5, 6)};
  f.results.save_optimized_poses(f.job, poses);
  std::vector<Eigen::Isometry3d> loaded = f.results.load_optimized_poses(f.job);
  ASSERT_EQ(loaded.size(), 2u);
  for (int i = 0; i < 2; ++i) expect_same_pose(loaded[i], poses[i]);
  EXPECT_THROW(f.results.save_optimized_poses(f.job, {poses[0], poses[1], poses[0]}), DatabaseError);  // no submap 2

  const TileKey key{"geotiff", 3, -2, 7};
  f.results.put_tile(f.job, key, {'I', 'I', 42, 0});
  f.results.put_tile(f.job, key, {'I', 'I', 42, 0, 8});  // replaced
  EXPECT_EQ(f.results.tile(f.job, key), (Bytes{'I', 'I', 42, 0, 8}));
  EXPECT_EQ(f.results.tile(f.job, {"openvdb", 3, -2, 7}), std::nullopt);
  EXPECT_THROW(f.results.put_tile(f.job, {"jpeg", 0, 0, 0}, {}), std::invalid_argument);

  Report report{{{"consistency", {{"rmse_m", 0.21}}}, {"configuration", "gicp"}},
                {{"histogram.png", {0x89, 'P', 'N', 'G'}}, {"trajectory.png", {0x89, 'P'}}}};
  f.results.save_report(f.job, report);
  std::optional<Report> back = f.results.load_report(f.job);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->report, report.report);
  EXPECT_EQ(back->plots, report.plots);
  EXPECT_EQ(f.results.load_report(f.job + 1), std::nullopt);
}

// Files are stored and read back in chunks (three here: 7, 7 and 5 bytes), and replaced by name.
TEST(ResultStore, FilesRoundTripInChunks) {
  testing::FreshDatabase db;
  ConnectionPool pool{db.conninfo(), 2};
  SurveyStore surveys{pool};
  JobQueue jobs{pool};
  ResultStore results{pool, 7};
  const std::int64_t job = jobs.enqueue({surveys.create_survey(surveys.create_tenant("acme"), "lake", {{"nav.csv", {1}}}), "gicp"});
  const std::filesystem::path path = std::filesystem::temp_directory_path() / ("job_file_" + std::to_string(::getpid()));
  auto write = [&](const std::string& text) { std::ofstream(path, std::ios::binary) << text; };
  auto read = [&](const std::string& name, std::vector<std::size_t>* sizes = nullptr) {
    std::string text;
    const bool found = results.read_file(job, name, [&](const Bytes& chunk) {
      text.append(chunk.begin(), chunk.end());
      if (sizes) sizes->push_back(chunk.size());
    });
    return found ? std::optional<std::string>(text) : std::nullopt;
  };
  write("GSF-v03.11 and more");
  results.put_file(job, "corrected.gsf", path);
  EXPECT_EQ(results.file_size(job, "corrected.gsf"), 19);
  std::vector<std::size_t> sizes;
  EXPECT_EQ(read("corrected.gsf", &sizes), "GSF-v03.11 and more");
  EXPECT_EQ(sizes, (std::vector<std::size_t>{7, 7, 5}));
  write("short");
  results.put_file(job, "corrected.gsf", path);  // replaced
  EXPECT_EQ(read("corrected.gsf"), "short");
  EXPECT_EQ(results.file_size(job, "other.gsf"), std::nullopt);
  EXPECT_EQ(read("other.gsf"), std::nullopt);
  EXPECT_THROW(results.put_file(job, "../escape", path), DatabaseError);  // plain names only
  results.discard(job);
  EXPECT_EQ(results.file_size(job, "corrected.gsf"), std::nullopt);
  EXPECT_EQ(db.scalar("SELECT count(*) FROM job_file_chunks"), 0);
  std::filesystem::remove(path);
}

TEST(ResultStore, AnAttemptStoppedWhileStoringLeavesNothingTheNextOneCollidesWith) {
  JobFixture f;
  const std::int64_t other = f.jobs.enqueue({f.survey, "mchs"});
  for (std::int64_t job : {f.job, other}) {
    f.results.save_origin(job, {451000, 4629000});
    f.results.save_submaps(job, {a_submap(0, true), a_submap(1, true)});
    f.results.save_optimized_poses(job, {a_pose(0, 0, 0, 0), a_pose(0, 1, 0, 0)});
    f.results.put_tile(job, {"png", 0, 0, 0}, {1});
    f.results.save_report(job, {{{"ok", true}}, {{"plot.png", {1}}}});
  }
  EXPECT_THROW(f.results.save_submaps(f.job, {a_submap(0, true)}), DatabaseError);  // what a rerun met

  f.results.discard(f.job);
  EXPECT_TRUE(f.results.load_submaps(f.job).empty());
  EXPECT_TRUE(f.results.tiles(f.job).empty());
  EXPECT_EQ(f.results.load_report(f.job), std::nullopt);
  EXPECT_EQ(f.results.origin(f.job), std::nullopt);
  f.results.save_submaps(f.job, {a_submap(0, true), a_submap(1, true)});  // the next attempt stores
  f.results.save_report(f.job, {{{"ok", true}}, {}});
  // Another job's results are untouched.
  EXPECT_EQ(f.results.load_submaps(other).size(), 2u);
  EXPECT_EQ(f.results.tiles(other).size(), 1u);
  EXPECT_TRUE(f.results.load_report(other));
}

// Jobs that resume: a running attempt stores each registered batch under its lease; the next
// attempt reads them back by batch start. The store's discard (its first step) keeps them, for an
// attempt killed while it stores; the job's end removes them (a cancel: OnlyACancelledJobs...).
TEST(ResultStore, CheckpointsAreKeptUnderTheLeaseForTheNextAttempt) {
  JobFixture f;
  f.pool.acquire()->exec("UPDATE jobs SET max_attempts = 2");
  std::optional<ClaimedJob> first = f.jobs.claim("first");
  ASSERT_TRUE(first);
  ResultStore running = f.results.fenced(first->lease);
  running.save_checkpoint(f.job, 12, 24, {4, 5, 6});
  running.save_checkpoint(f.job, 0, 12, {1, 2});
  running.save_checkpoint(f.job, 12, 24, {7, 8, 9});  // the same batch registered again replaces it
  EXPECT_EQ(f.results.load_checkpoints(f.job), (std::vector<Bytes>{{1, 2}, {7, 8, 9}}));

  f.pool.acquire()->exec("UPDATE jobs SET lease_expires_at = now() - interval '1 s' WHERE id = $1", {f.job});
  ASSERT_EQ(f.jobs.reap(), 1);
  EXPECT_THROW(running.save_checkpoint(f.job, 24, 36, {1}), LeaseLost);  // no longer its job
  std::optional<ClaimedJob> second = f.jobs.claim("second");
  ASSERT_TRUE(second);
  EXPECT_EQ(f.results.load_checkpoints(f.job).size(), 2u);  // what the next attempt takes up
  ResultStore next = f.results.fenced(second->lease);
  next.save_checkpoint(f.job, 24, 36, {3});
  EXPECT_THROW(next.save_checkpoint(f.job, 5, 5, {1}), DatabaseError);  // an empty batch
  next.discard(f.job);
  EXPECT_EQ(f.results.load_checkpoints(f.job).size(), 3u);
  ASSERT_TRUE(f.jobs.succeed(second->lease));
  EXPECT_TRUE(f.results.load_checkpoints(f.job).empty());
}

// A job the reaper fails for good (its attempts used up) ends like one that finished: no attempt
// will take its checkpoints up, so they go with the same statement.
TEST(ResultStore, AJobTheReaperFailsForGoodLeavesNoCheckpoints) {
  JobFixture f;
  f.pool.acquire()->exec("UPDATE jobs SET max_attempts = 2");
  for (const char* worker : {"first", "second"}) {
    std::optional<ClaimedJob> claimed = f.jobs.claim(worker);
    ASSERT_TRUE(claimed);
    f.results.fenced(claimed->lease).save_checkpoint(f.job, 0, 12, {1, 2});
    f.pool.acquire()->exec("UPDATE jobs SET lease_expires_at = now() - interval '1 s' WHERE id = $1", {f.job});
    ASSERT_EQ(f.jobs.reap(), 1);
    // Re-queued after the first attempt: kept for the second; failed after the second: gone.
    EXPECT_EQ(f.results.load_checkpoints(f.job).size(), std::string(worker) == "first" ? 1u : 0u) << worker;
  }
  EXPECT_EQ(f.jobs.status(f.job).state, JobState::kFailed);
}

// A worker whose lease was reaped while it stored must neither add to nor discard the results
// of the attempt that took the job over.
TEST(ResultStore, AWorkerThatLostItsLeaseWritesNothing) {
  JobFixture f;
  f.pool.acquire()->exec("UPDATE jobs SET max_attempts = 2");
  std::optional<ClaimedJob> first = f.jobs.claim("first");
  ASSERT_TRUE(first);
  ResultStore late = f.results.fenced(first->lease);
  late.save_submaps(f.job, {a_submap(0, true), a_submap(1, true)});  // while it holds the lease
  f.pool.acquire()->exec("UPDATE jobs SET lease_expires_at = now() - interval '1 s' WHERE id = $1", {f.job});
  ASSERT_EQ(f.jobs.reap(), 1);
  std::optional<ClaimedJob> second = f.jobs.claim("second");
  ASSERT_TRUE(second);
  ResultStore current = f.results.fenced(second->lease);
  current.discard(f.job);
  current.save_submaps(f.job, {a_submap(0, false), a_submap(1, false), a_submap(2, false)});
  current.save_report(f.job, {{{"attempt", 2}}, {}});

  EXPECT_THROW(late.discard(f.job), LeaseLost);
  EXPECT_THROW(late.save_origin(f.job, {1, 2}), LeaseLost);
  EXPECT_THROW(late.save_optimized_poses(f.job, {a_pose(0, 0, 0, 0)}), LeaseLost);
  EXPECT_THROW(late.put_tile(f.job, {"png", 0, 0, 0}, {1}), LeaseLost);
  EXPECT_THROW(late.save_map_grid(f.job, {32651, 0.5, 0, 0, 1, 1, 512, 1}), LeaseLost);
  EXPECT_THROW(late.save_report(f.job, {{{"attempt", 1}}, {}}), LeaseLost);
  EXPECT_EQ(f.results.load_submaps(f.job).size(), 3u);
  EXPECT_EQ(f.results.load_report(f.job)->report, (nlohmann::json{{"attempt", 2}}));
  EXPECT_TRUE(f.results.tiles(f.job).empty());
  EXPECT_EQ(f.results.origin(f.job), std::nullopt);
  EXPECT_THROW(current.save_optimized_poses(f.job + 1, {}), std::invalid_argument);  // its own job only
  // Once the job has ended, no lease is held at all.
  ASSERT_TRUE(f.jobs.succeed(second->lease));
  EXPECT_THROW(current.put_tile(f.job, {"png", 0, 0, 0}, {1}), LeaseLost);
}

// Withdrawing takes only a cancelled job's results: a running one's (or a reaped one's, which
// its next attempt discards itself) stay.
TEST(ResultStore, OnlyACancelledJobsResultsAreWithdrawn) {
  JobFixture f;
  std::optional<ClaimedJob> claimed = f.jobs.claim("worker");
  ASSERT_TRUE(claimed);
  ResultStore fenced = f.results.fenced(claimed->lease);
  fenced.save_origin(f.job, {451000, 4629000});
  fenced.save_submaps(f.job, {a_submap(0, true)});
  fenced.put_tile(f.job, {"png", 0, 0, 0}, {1});
  fenced.save_report(f.job, {{{"ok", true}}, {}});
  fenced.save_checkpoint(f.job, 0, 12, {1});

  EXPECT_FALSE(f.results.discard_if_cancelled(f.job));
  EXPECT_EQ(f.results.load_submaps(f.job).size(), 1u);
  ASSERT_TRUE(f.jobs.cancel(f.job));
  EXPECT_TRUE(f.results.discard_if_cancelled(f.job));
  EXPECT_TRUE(f.results.load_checkpoints(f.job).empty());
  EXPECT_TRUE(f.results.load_submaps(f.job).empty());
  EXPECT_TRUE(f.results.tiles(f.job).empty());
  EXPECT_EQ(f.results.load_report(f.job), std::nullopt);
  EXPECT_EQ(f.results.origin(f.job), std::nullopt);
}

TEST(ResultStore, DeletingASurveyRemovesEverythingUnderIt) {
  JobFixture f;
  // A second survey of another tenant, with the same kinds of rows, must survive.
  const std::int64_t other = f.surveys.create_survey(f.surveys.create_tenant("other"), "pond", {{"nav.csv", {9}}});
  const std::int64_t other_job = f.jobs.enqueue({other, "odometry"});
  for (auto [survey, job] : {std::pair{f.survey, f.job}, std::pair{other, other_job}}) {
    f.surveys.save_validation(survey, {true, nlohmann::json::array(), nullptr});
    f.results.save_submaps(job, {a_submap(0, true), a_submap(1, true)});
    Constraint odometry;
    odometry.to = 1;
    f.results.save_constraints(job, {odometry});
    f.results.save_optimized_poses(job, {a_pose(0, 0, 0, 0), a_pose(0, 1, 0, 0)});
    f.results.put_tile(job, {"openvdb", 0, 0, 0}, {1});
    f.results.save_report(job, {{{"ok", true}}, {{"plot.png", {1}}}});
  }
  std::optional<ClaimedJob> claimed = f.jobs.claim("w");
  ASSERT_TRUE(claimed);
  f.jobs.record_event(claimed->lease, "submaps", 0.1);

  const std::vector<std::string> tables = {"survey_files", "survey_file_chunks", "survey_validations", "jobs",
                                           "job_events", "submaps", "constraints", "optimized_poses", "tiles",
                                           "reports", "report_plots"};
  auto count = [&](const std::string& table) { return f.db.scalar("SELECT count(*) FROM " + table); };
  std::map<std::string, long long> before;
  for (const std::string& table : tables) before[table] = count(table);

  EXPECT_TRUE(f.surveys.delete_survey(f.survey));
  EXPECT_FALSE(f.surveys.delete_survey(f.survey));
  EXPECT_EQ(count("surveys"), 1);
  EXPECT_EQ(count("tenants"), 2);  // a tenant outlives its surveys
  for (const std::string& table : tables) {
    SCOPED_TRACE(table);
    EXPECT_GT(before[table], count(table));
    // ... while the other survey keeps its own.
    if (table != "job_events") {
      EXPECT_GT(count(table), 0);
    }
  }
  EXPECT_EQ(f.results.load_submaps(f.job).size(), 0u);
  EXPECT_EQ(f.results.load_submaps(other_job).size(), 2u);
}

}  // namespace
}  // namespace bathyslam::storage
