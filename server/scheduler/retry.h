#pragma once
// Retrying work that failed only because the database was briefly away (a restart, a failover,
// a lost connection): the same call is tried again after a growing wait, for a bounded time.
// Any other error, or a transient one once the time is up, goes to the caller.
#include <atomic>
#include <chrono>
#include <string>
#include <type_traits>

#include "core/pipeline/pipeline.h"
#include "server/log.h"
#include "server/storage/database.h"

namespace bathyslam::server {

struct RetryPolicy {
  std::chrono::milliseconds first_wait{500};
  std::chrono::milliseconds max_wait{5'000};
  std::chrono::milliseconds give_up_after{60'000};  // of waiting, counted from the first failure
};

// Sleeps `duration`, in slices so that `stop` ends the wait early; false when it did.
bool sleep_unless(const std::atomic<bool>& stop, std::chrono::milliseconds duration);

// Runs `body` until it returns, retrying after transient database errors as `policy` allows.
// `stop` (the job was cancelled, or the server is stopping) ends the retries with Cancelled.
// `what` names the work in the log ("job 7: storing results").
template <typename Body>
auto retry_transient(const std::string& what, const RetryPolicy& policy, const std::atomic<bool>& stop, Body&& body) {
  using Clock = std::chrono::steady_clock;
  std::chrono::milliseconds wait = policy.first_wait;
  Clock::time_point first_failure{};
  for (int failures = 0;; ++failures) {
    try {
      auto finish = [&] {
        if (failures > 0) log("%s: succeeded after %d transient database failures", what.c_str(), failures);
      };
      if constexpr (std::is_void_v<decltype(body())>) {
        body();
        finish();
        return;
      } else {
        auto result = body();
        finish();
        return result;
      }
    } catch (const storage::DatabaseError& error) {
      if (!error.transient()) throw;
      if (failures == 0) first_failure = Clock::now();
      if (Clock::now() - first_failure + wait > policy.give_up_after) throw;
      log("%s: %s; trying again in %.1f s", what.c_str(), error.what(), wait.count() / 1000.0);
      if (!sleep_unless(stop, wait)) throw Cancelled();
      wait = std::min(policy.max_wait, wait * 2);
    }
  }
}

// Logs the first of a run of failures of the same kind and the recovery after it, not every one
// in between: a watcher polling every 200 ms through a 30 s outage would write 150 lines.
class FailureStreak {
 public:
  explicit FailureStreak(std::string what) : what_(std::move(what)) {}
  void failed(const char* error) {
    if (failures_++ == 0) log("%s failed: %s (logged once until it works again)", what_.c_str(), error);
  }
  void succeeded() {
    if (failures_ > 0) log("%s works again after %d failures", what_.c_str(), failures_);
    failures_ = 0;
  }

 private:
  std::string what_;
  int failures_ = 0;
};

}  // namespace bathyslam::server
