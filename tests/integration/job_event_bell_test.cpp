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
  bool listening = false;
  for (int i = 0; i < 50 && !listening; ++i) {
    const std::int64_t probe = queue.enqueue({survey, "odometry"});
    queue.cancel(probe);
    bell.wait(probe, 0, 200ms);
    listening = bell.rings(probe) > 0;
  }
  ASSERT_TRUE(listening) << "the bell never heard a notification";

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
  EXPECT_EQ(bell.rings(other), 0u);
}

}  // namespace
}  // namespace bathyslam::server
