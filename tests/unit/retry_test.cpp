// retry_transient: what the scheduler and the services do when the database is briefly away.
#include "server/scheduler/retry.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

namespace bathyslam::server {
namespace {

const RetryPolicy kQuick{std::chrono::milliseconds(1), std::chrono::milliseconds(4), std::chrono::milliseconds(2'000)};

storage::DatabaseError lost_connection() { return storage::DatabaseError("08006", "connection to server was lost"); }

TEST(RetryTransient, TriesAgainAfterTransientErrorsAndReturnsTheResult) {
  std::atomic<bool> stop{false};
  int calls = 0;
  const int answer = retry_transient("test", kQuick, stop, [&] {
    if (++calls < 3) throw lost_connection();
    return 42;
  });
  EXPECT_EQ(answer, 42);
  EXPECT_EQ(calls, 3);
}

TEST(RetryTransient, PassesAnyOtherErrorOnAtOnce) {
  std::atomic<bool> stop{false};
  int calls = 0;
  const auto unique_violation = [&] {
    ++calls;
    throw storage::DatabaseError("23505", "duplicate key value violates unique constraint");
  };
  EXPECT_THROW(retry_transient("test", kQuick, stop, unique_violation), storage::DatabaseError);
  EXPECT_EQ(calls, 1);
  calls = 0;
  EXPECT_THROW(retry_transient("test", kQuick, stop, [&] { ++calls, throw std::runtime_error("not the database"); }),
               std::runtime_error);
  EXPECT_EQ(calls, 1);
}

TEST(RetryTransient, GivesUpWhenTheOutageOutlastsThePolicy) {
  std::atomic<bool> stop{false};
  const RetryPolicy brief{std::chrono::milliseconds(1), std::chrono::milliseconds(4), std::chrono::milliseconds(30)};
  int calls = 0;
  const auto start = std::chrono::steady_clock::now();
  try {
    retry_transient("test", brief, stop, [&] { ++calls, throw lost_connection(); });
    FAIL() << "an outage longer than the policy must reach the caller";
  } catch (const storage::DatabaseError& error) {
    EXPECT_TRUE(error.transient());
  }
  EXPECT_GT(calls, 2);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));
}

TEST(RetryTransient, StopsWaitingWhenTheJobIsCancelled) {
  std::atomic<bool> stop{false};
  const RetryPolicy patient{std::chrono::milliseconds(10'000), std::chrono::milliseconds(10'000),
                            std::chrono::milliseconds(60'000)};
  std::thread canceller([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    stop = true;
  });
  const auto start = std::chrono::steady_clock::now();
  EXPECT_THROW(retry_transient("test", patient, stop, [&] { throw lost_connection(); }), Cancelled);
  canceller.join();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5)) << "not the 10 s wait";
}

}  // namespace
}  // namespace bathyslam::server
