// WatchJob's bell against a real PostgreSQL: the triggers of migration 0004 ring it for a job's
// events and state changes, and only that job's count moves.
#include <chrono>
#include <optional>

#include <gtest/gtest.h>

#include "server/services/job_event_bell.h"
#include "server/storage/job_queue.h"
#include "server/storage/survey_store.h"
#include "tests/integration/fresh_database.h"

namespace bathyslam::server {
namespace {

using namespace std::chrono_literals;

TEST(JobEventBell, AJobsEventsAndStateChangesRingItsBellAndNoOtherJobs) {
  testing::FreshDatabase db;
  storage::ConnectionPool pool(db.conninfo(), 2);
  storage::SurveyStore surveys(pool);
  storage::JobQueue queue(pool);
  const std::int64_t survey = surveys.create_survey(surveys.create_tenant("acme"), "lake", {});
  const std::int64_t watched = queue.enqueue({survey, "gicp"});
  const std::int64_t other = queue.enqueue({survey, "gicp"});
  JobEventBell bell(db.conninfo());
  // Its LISTEN comes up on its own thread: cancel throwaway jobs until one rings.
  bool heard = false;
  for (int i = 0; i < 50 && !heard; ++i) {
    const std::int64_t probe = queue.enqueue({survey, "odometry"});
    const std::uint64_t before = bell.rings(probe);
    queue.cancel(probe);
    bell.wait(probe, before, 200ms);
    heard = bell.rings(probe) > before;
  }
  ASSERT_TRUE(heard) << "the bell never heard a notification";
  const std::uint64_t quiet = bell.rings(other);

  std::uint64_t seen = bell.rings(watched);
  std::optional<storage::ClaimedJob> job = queue.claim("w");  // queued -> running
  ASSERT_TRUE(job);
  ASSERT_EQ(job->lease.job_id, watched);
  bell.wait(watched, seen, 10s);
  EXPECT_GT(bell.rings(watched), seen) << "a state change did not ring";

  seen = bell.rings(watched);
  ASSERT_TRUE(queue.record_event(job->lease, "register", 0.5));
  bell.wait(watched, seen, 10s);
  EXPECT_GT(bell.rings(watched), seen) << "an event did not ring";

  seen = bell.rings(watched);
  ASSERT_TRUE(queue.succeed(job->lease));
  bell.wait(watched, seen, 10s);
  EXPECT_GT(bell.rings(watched), seen) << "the final state did not ring";
  EXPECT_EQ(bell.rings(other), quiet);
}

// Issue 37 fault 1: watchers that wait cost the database nothing. While the bell listens, a
// wait that nothing rang through says so (no need to read the job); a bell that cannot listen
// has its watchers poll.
TEST(JobEventBell, AWatcherNeedNotLookWhileTheBellListensAndPollsWhileItCannot) {
  testing::FreshDatabase db;
  storage::ConnectionPool pool(db.conninfo(), 1);
  storage::SurveyStore surveys(pool);
  storage::JobQueue queue(pool);
  const std::int64_t job = queue.enqueue({surveys.create_survey(surveys.create_tenant("acme"), "lake", {}), "gicp"});
  JobEventBell bell(db.conninfo());
  bell.wait(job, 0, 10s);
  ASSERT_GT(bell.rings(job), 0u) << "the bell never started listening";  // its start moves every count
  EXPECT_FALSE(bell.wait(job, bell.rings(job), 300ms)) << "nothing rang, yet the watcher is sent to look";
  const std::uint64_t seen = bell.rings(job);
  ASSERT_TRUE(queue.cancel(job));
  EXPECT_TRUE(bell.wait(job, seen, 10s)) << "the job rang, yet the watcher is not sent to look";

  JobEventBell deaf("host=/nonexistent-socket-folder dbname=none connect_timeout=1");
  EXPECT_TRUE(deaf.wait(job, deaf.rings(job), 300ms)) << "a bell that cannot listen must have its watchers poll";
}

}  // namespace
}  // namespace bathyslam::server
