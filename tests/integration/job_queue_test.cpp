// The job queue under the conditions it exists for: racing workers, dead workers, idle workers.
#include <algorithm>
#include <atomic>
#include <barrier>
#include <chrono>
#include <cstdio>
#include <set>
#include <thread>

#include <gtest/gtest.h>

#include "server/storage/job_queue.h"
#include "server/storage/survey_store.h"
#include "tests/integration/fresh_database.h"

namespace bathyslam::storage {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

std::int64_t a_survey(ConnectionPool& pool) {
  SurveyStore surveys(pool);
  return surveys.create_survey(surveys.create_tenant("acme"), "lake", {});
}

TEST(JobQueue, TwoWorkersRacingFor200JobsNeverShareOneAndFinishAll) {
  testing::FreshDatabase db;
  ConnectionPool setup(db.conninfo(), 1);
  const std::int64_t survey = a_survey(setup);
  JobQueue producer(setup);
  std::set<std::int64_t> enqueued;
  for (int i = 0; i < 200; ++i) enqueued.insert(producer.enqueue({survey, "gicp", {{"n", i}}}));

  std::vector<std::int64_t> done[2];
  std::barrier start(2);
  Clock::time_point finished[2];
  const auto begin = Clock::now();
  auto worker = [&](int w) {
    ConnectionPool pool(db.conninfo(), 1);  // a worker of its own: separate connections
    JobQueue queue(pool, {.lease = 30s, .poll = 100ms});
    const std::string name = "worker-" + std::to_string(w);
    start.arrive_and_wait();
    while (auto job = queue.wait_for_job(name, 300ms)) {
      EXPECT_TRUE(queue.heartbeat(job->lease));
      EXPECT_TRUE(queue.succeed(job->lease));
      done[w].push_back(job->lease.job_id);
      finished[w] = Clock::now();
    }
  };
  std::thread a(worker, 0), b(worker, 1);
  a.join();
  b.join();

  std::set<std::int64_t> all(done[0].begin(), done[0].end());
  for (std::int64_t id : done[1]) EXPECT_TRUE(all.insert(id).second) << "job " << id << " claimed twice";
  EXPECT_EQ(done[0].size() + done[1].size(), 200u);
  EXPECT_EQ(all, enqueued);
  EXPECT_EQ(db.scalar("SELECT count(*) FROM jobs WHERE state = 'succeeded' AND attempts = 1"), 200);
  const double seconds = std::chrono::duration<double>(std::max(finished[0], finished[1]) - begin).count();
  std::printf("200 jobs: worker-0 %zu, worker-1 %zu, %.2f s, %.0f claim+heartbeat+succeed per second\n",
              done[0].size(), done[1].size(), seconds, 200 / seconds);
}

TEST(JobQueue, AnAbandonedLeaseIsReapedAndTheJobFinishedByAnotherWorker) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 2);
  JobQueue queue(pool, {.lease = 1s, .poll = 200ms});
  const std::int64_t id = queue.enqueue({a_survey(pool), "mchs"});

  std::optional<ClaimedJob> lost = queue.claim("crashed");
  ASSERT_TRUE(lost);
  EXPECT_EQ(queue.reap(), 0);  // the lease is still good
  // "crashed" never heartbeats again. Another worker waits, the reaper re-queues, it claims.
  const auto begin = Clock::now();
  std::optional<ClaimedJob> job = queue.wait_for_job("rescuer", 5s);
  ASSERT_TRUE(job);
  EXPECT_GE(Clock::now() - begin, 800ms);
  EXPECT_EQ(job->lease.job_id, id);
  EXPECT_EQ(job->lease.attempt, 2);
  // The dead worker, should it come back, can no longer touch the job.
  EXPECT_FALSE(queue.heartbeat(lost->lease));
  EXPECT_FALSE(queue.succeed(lost->lease));
  EXPECT_FALSE(queue.record_event(lost->lease, "register", 0.5));
  EXPECT_TRUE(queue.record_event(job->lease, "register", 0.5, "halfway"));
  EXPECT_TRUE(queue.succeed(job->lease));

  JobStatus status = queue.status(id);
  EXPECT_EQ(status.state, JobState::kSucceeded);
  EXPECT_EQ(status.attempts, 2);
  EXPECT_EQ(status.worker, "rescuer");
  std::vector<JobEvent> events = queue.events(id);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].stage, "lease-expired");
  EXPECT_EQ(events[0].attempt, 1);
  EXPECT_EQ(events[1].stage, "register");
  EXPECT_EQ(events[1].progress, 0.5);
  EXPECT_EQ(events[1].message, "halfway");
}

TEST(JobQueue, AJobFailsWithTheReasonOnceItsAttemptsAreUsedUp) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 2);
  JobQueue queue(pool, {.lease = 1s, .poll = 200ms});
  const std::int64_t id = queue.enqueue({a_survey(pool), "gicp", {}, 2});
  ASSERT_TRUE(queue.claim("first"));
  std::this_thread::sleep_for(1100ms);
  EXPECT_EQ(queue.reap(), 1);
  ASSERT_TRUE(queue.claim("second"));
  std::this_thread::sleep_for(1100ms);
  EXPECT_EQ(queue.reap(), 1);
  EXPECT_FALSE(queue.claim("third"));

  JobStatus status = queue.status(id);
  EXPECT_EQ(status.state, JobState::kFailed);
  EXPECT_EQ(status.attempts, 2);
  ASSERT_TRUE(status.error);
  EXPECT_EQ(*status.error, "lease of worker second expired on attempt 2 of 2; giving up");
}

TEST(JobQueue, AJobGivenBackByAStoppingServerIsClaimedAtOnceAndKeepsItsAttempts) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 3);
  JobQueue queue(pool, {.lease = 30s, .poll = 20s});
  const std::int64_t id = queue.enqueue({a_survey(pool), "gicp", {}, 1});
  std::optional<ClaimedJob> stopped = queue.claim("stopping");
  ASSERT_TRUE(stopped);

  // An idle worker already waiting is woken by the give-back's NOTIFY, long before the 30 s
  // lease would have run out or its 20 s poll come round.
  std::optional<ClaimedJob> job;
  std::thread next([&] { job = queue.wait_for_job("next", 10s); });
  std::this_thread::sleep_for(300ms);
  const auto released_at = Clock::now();
  EXPECT_TRUE(queue.release(stopped->lease));
  next.join();
  ASSERT_TRUE(job);
  EXPECT_LT(Clock::now() - released_at, 2s);
  EXPECT_EQ(job->lease.job_id, id);
  EXPECT_EQ(job->lease.attempt, 2);  // a new attempt, one more allowed: the stop used none up
  EXPECT_FALSE(queue.release(stopped->lease));  // no longer its job
  EXPECT_FALSE(queue.heartbeat(stopped->lease));
  std::vector<JobEvent> events = queue.events(id);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].stage, "released");
  EXPECT_EQ(events[0].message, "worker stopping stopped with its server; re-queued");
  EXPECT_TRUE(queue.succeed(job->lease));
  EXPECT_EQ(queue.status(id).state, JobState::kSucceeded);
}

TEST(JobQueue, AJobGivenBackAfterAnOutageUsesItsAttemptAndFailsWhenNoneAreLeft) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 2);
  JobQueue queue(pool, {.lease = 30s, .poll = 200ms});
  const std::int64_t id = queue.enqueue({a_survey(pool), "gicp", {}, 2});
  std::optional<ClaimedJob> first = queue.claim("first");
  ASSERT_TRUE(first);
  EXPECT_TRUE(queue.requeue_after_outage(first->lease));
  EXPECT_FALSE(queue.requeue_after_outage(first->lease));  // no longer its job
  EXPECT_EQ(queue.status(id).state, JobState::kQueued);
  std::optional<ClaimedJob> second = queue.claim("second");
  ASSERT_TRUE(second);
  EXPECT_EQ(second->lease.attempt, 2);
  EXPECT_TRUE(queue.requeue_after_outage(second->lease));
  const JobStatus status = queue.status(id);
  EXPECT_EQ(status.state, JobState::kFailed);
  ASSERT_TRUE(status.error);
  EXPECT_EQ(*status.error, "worker second lost the database while running it on attempt 2 of 2; giving up");
  std::vector<JobEvent> events = queue.events(id);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].stage, "requeued");
  EXPECT_EQ(events[0].message, "worker first lost the database while running it; re-queued");
}

TEST(JobQueue, TheActiveJobLimitHoldsUnderConcurrentSubmits) {
  testing::FreshDatabase db;
  ConnectionPool setup(db.conninfo(), 1);
  SurveyStore surveys(setup);
  const std::int64_t tenant = surveys.create_tenant("acme");
  const std::int64_t survey = surveys.create_survey(tenant, "lake", {});
  constexpr int kSubmitters = 8, kLimit = 3;
  std::atomic<int> accepted{0};
  std::barrier start(kSubmitters);
  std::vector<std::thread> submitters;
  for (int i = 0; i < kSubmitters; ++i)
    submitters.emplace_back([&] {
      ConnectionPool pool(db.conninfo(), 1);  // a connection each, as concurrent requests have
      JobQueue queue(pool);
      start.arrive_and_wait();
      if (queue.enqueue_within_limit({survey, "gicp"}, tenant, kLimit)) ++accepted;
    });
  for (std::thread& submitter : submitters) submitter.join();
  EXPECT_EQ(accepted, kLimit);
  JobQueue queue(setup);
  EXPECT_EQ(queue.active_jobs(tenant), kLimit);
  // Another tenant has a limit of its own.
  const std::int64_t other = surveys.create_tenant("other");
  EXPECT_TRUE(queue.enqueue_within_limit({surveys.create_survey(other, "lake", {}), "gicp"}, other, kLimit));
}

TEST(DatabaseError, ALostConnectionIsTransientAConstraintViolationIsNot) {
  EXPECT_TRUE(DatabaseError("08006", "connection failure").transient());
  EXPECT_TRUE(DatabaseError("57P01", "terminating connection due to administrator command").transient());
  EXPECT_TRUE(DatabaseError("40001", "could not serialize access").transient());
  EXPECT_FALSE(DatabaseError("23505", "duplicate key").transient());
  EXPECT_FALSE(DatabaseError("22P02", "invalid input syntax").transient());
}

TEST(JobQueue, HeartbeatsKeepALeaseAlivePastItsFirstExpiry) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 2);
  JobQueue queue(pool, {.lease = 2s, .poll = 200ms});
  queue.enqueue({a_survey(pool), "gicp"});
  std::optional<ClaimedJob> job = queue.claim("steady");
  ASSERT_TRUE(job);
  for (int i = 0; i < 5; ++i) {  // 2.5 s in all, beats 1.5 s inside the lease: robust to a slow machine
    std::this_thread::sleep_for(500ms);
    ASSERT_TRUE(queue.heartbeat(job->lease));
    EXPECT_EQ(queue.reap(), 0);
  }
  EXPECT_TRUE(queue.succeed(job->lease));
}

// A worker storing results holds its lease through the transaction (hold_lease). On `large` a
// store took over a minute: its heartbeats must go on meanwhile, and so must a cancel, while the
// reaper still cannot take the job from under the store.
TEST(JobQueue, AStoreHoldingItsLeaseStopsTheReaperButNotHeartbeatsOrACancel) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 3, {.statement_timeout = 3s});
  JobQueue queue(pool, {.lease = 1s, .poll = 200ms});
  const std::int64_t survey = a_survey(pool);
  const std::int64_t stored = queue.enqueue({survey, "mchs"});
  std::optional<ClaimedJob> job = queue.claim("storing");
  ASSERT_TRUE(job);
  {
    auto storing = pool.acquire();
    Transaction transaction(*storing);
    ASSERT_TRUE(hold_lease(*storing, job->lease));
    const auto begin = Clock::now();
    EXPECT_TRUE(queue.heartbeat(job->lease));  // under FOR SHARE: waits, then the statement timeout
    EXPECT_LT(Clock::now() - begin, 2s);
    std::this_thread::sleep_for(1100ms);  // no heartbeat since: the lease has expired
    EXPECT_EQ(queue.reap(), 0);           // but the store holds it
    transaction.commit();
  }
  EXPECT_EQ(queue.reap(), 1);  // once stored, an expired lease is reaped as ever
  EXPECT_EQ(queue.status(stored).state, JobState::kQueued);

  job = queue.claim("storing again");
  ASSERT_TRUE(job);
  auto storing = pool.acquire();
  Transaction transaction(*storing);
  ASSERT_TRUE(hold_lease(*storing, job->lease));
  const auto begin = Clock::now();
  EXPECT_TRUE(queue.cancel(stored));
  EXPECT_LT(Clock::now() - begin, 2s);
  EXPECT_FALSE(queue.heartbeat(job->lease));  // the cancel took the lease
}

TEST(JobQueue, AnEnqueueWakesAnIdleWorkerWithoutWaitingForThePoll) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 2);
  const std::int64_t survey = a_survey(pool);
  JobQueue queue(pool, {.lease = 30s, .poll = 20s});
  std::optional<ClaimedJob> job;
  Clock::duration waited{};
  std::thread worker([&] {
    const auto begin = Clock::now();
    job = queue.wait_for_job("sleeper", 15s);
    waited = Clock::now() - begin;
  });
  std::this_thread::sleep_for(300ms);
  const auto enqueued_at = Clock::now();
  queue.enqueue({survey, "odometry"});
  worker.join();
  ASSERT_TRUE(job);
  EXPECT_GE(waited, 250ms);
  EXPECT_LT(Clock::now() - enqueued_at, 2s) << "woken by the poll, not by NOTIFY";
}

TEST(JobQueue, CancellingARunningJobTakesItsLeaseAway) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 2);
  JobQueue queue(pool);
  const std::int64_t survey = a_survey(pool);
  const std::int64_t queued = queue.enqueue({survey, "gicp"});
  const std::int64_t running = queue.enqueue({survey, "gicp"});
  EXPECT_TRUE(queue.cancel(queued));
  std::optional<ClaimedJob> job = queue.claim("busy");
  ASSERT_TRUE(job);
  EXPECT_EQ(job->lease.job_id, running);  // the cancelled one is never claimed
  EXPECT_TRUE(queue.cancel(running));
  EXPECT_FALSE(queue.heartbeat(job->lease));
  EXPECT_FALSE(queue.succeed(job->lease));
  EXPECT_FALSE(queue.cancel(running));  // already final
  EXPECT_EQ(queue.status(running).state, JobState::kCancelled);
}

TEST(JobQueue, AWorkersOwnFailureIsFinalAndKeepsTheMessage) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  JobQueue queue(pool);
  const std::int64_t id = queue.enqueue({a_survey(pool), "gicp", {{"gicp.max_iterations", 10}}});
  std::optional<ClaimedJob> job = queue.claim("w");
  ASSERT_TRUE(job);
  EXPECT_EQ(job->parameters["gicp.max_iterations"], 10);
  EXPECT_TRUE(queue.fail(job->lease, "nav.csv:5: easting: not a number"));
  EXPECT_FALSE(queue.claim("w"));
  EXPECT_EQ(queue.status(id).error, "nav.csv:5: easting: not a number");
}

TEST(JobQueue, BadInputIsRefusedAndEnqueuesNothing) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  JobQueue queue(pool);
  const std::int64_t survey = a_survey(pool);
  EXPECT_THROW(queue.enqueue({survey, "magic"}), std::invalid_argument);
  EXPECT_THROW(queue.enqueue({survey, "gicp", {}, 0}), std::invalid_argument);
  EXPECT_THROW(queue.enqueue({survey, "gicp", nlohmann::json::array()}), std::invalid_argument);
  try {
    queue.enqueue({survey + 1000, "gicp"});
    FAIL() << "a job for a survey that does not exist";
  } catch (const DatabaseError& error) {
    EXPECT_EQ(error.sqlstate(), "23503");
  }
  EXPECT_EQ(db.scalar("SELECT count(*) FROM jobs"), 0);
  EXPECT_THROW(queue.status(12345), std::out_of_range);
}

}  // namespace
}  // namespace bathyslam::storage
