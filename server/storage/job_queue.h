#pragma once
// The job queue, in PostgreSQL so that any number of servers share it. A worker claims a job with
// a lease that its heartbeat renews; a worker that dies stops renewing, and the reaper puts the
// job back in the queue (or fails it once it has used up its attempts). Idle workers sleep on
// LISTEN and are woken by the NOTIFY of every enqueue; polling covers a missed notification.
#include <chrono>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/storage/database.h"

namespace bathyslam::storage {

enum class JobState { kQueued, kRunning, kSucceeded, kFailed, kCancelled };
std::string to_string(JobState state);
// Succeeded, failed or cancelled: the job will not change again.
inline bool finished(JobState state) { return state != JobState::kQueued && state != JobState::kRunning; }
JobState parse_job_state(std::string_view text);  // throws std::invalid_argument

// What kept a worker from finishing a job that is not the job's fault.
enum class Outage { kDatabase, kScratchDisk };

struct QueueOptions {
  std::chrono::milliseconds lease{30'000};  // a worker must heartbeat well within this
  std::chrono::milliseconds poll{5'000};    // longest sleep without a notification
};

struct NewJob {
  std::int64_t survey_id = 0;
  std::string configuration;  // odometry, gicp or mchs
  nlohmann::json parameters = nlohmann::json::object();  // the effective parameters
  int max_attempts = 3;
  // Several surveys of one site (issue 33): the others, joined after survey_id in this order.
  std::vector<std::int64_t> more_survey_ids = {};
  std::optional<std::int64_t> site_id = std::nullopt;  // the site it was submitted for
};

// One claim of one job. The attempt number tells a worker's claim apart from a later one of the
// same job, so that a worker whose lease was reaped can no longer touch the job.
struct Lease {
  std::int64_t job_id = 0;
  std::string worker;
  int attempt = 0;
};

// True when `lease` is still held, and then the job's row is locked (FOR KEY SHARE) until the
// caller's transaction ends: no reaper can take the lease away before the writes of that
// transaction commit. The holder's heartbeats do not wait for them (a store can take minutes,
// longer than the lease), nor does a cancel: a store in flight then commits just after the
// cancel, and its worker removes what the job stored (ResultStore::discard_if_cancelled, which
// waits for that commit). Call it inside a transaction.
bool hold_lease(Connection& connection, const Lease& lease);

// A write refused because the lease it was made under is no longer held.
class LeaseLost : public std::runtime_error {
 public:
  explicit LeaseLost(const Lease& lease);
};

struct ClaimedJob {
  Lease lease;
  std::int64_t survey_id = 0;
  std::vector<std::int64_t> more_survey_ids;
  std::string configuration;
  nlohmann::json parameters;
};

struct JobStatus {
  std::int64_t id = 0;
  std::int64_t survey_id = 0;
  std::string configuration;
  JobState state = JobState::kQueued;
  int attempts = 0;
  int max_attempts = 0;
  std::optional<std::string> worker;  // the last worker to claim it
  std::optional<std::string> error;
};

struct JobEvent {
  int attempt = 0;
  std::string stage;
  double progress = 0;
  std::string message;
};

// A job as the API shows it: its row, the tenant of its survey and its latest event.
struct JobRecord {
  std::int64_t id = 0;
  std::int64_t survey_id = 0;
  std::vector<std::int64_t> more_survey_ids;
  std::optional<std::int64_t> site_id;
  std::int64_t tenant_id = 0;
  std::string configuration;
  JobState state = JobState::kQueued;
  int attempts = 0;
  std::optional<std::string> error;
  nlohmann::json parameters;
  double created_at = 0, started_at = 0, finished_at = 0;  // seconds since the epoch; 0: not yet
  std::string stage;                                        // of the latest event, "" before any
  double progress = 0;
};

// An event with its id (WatchJob resumes after the last id it sent) and time.
struct StoredJobEvent {
  std::int64_t id = 0;
  JobEvent event;
  double at = 0;  // seconds since the epoch
};

class JobQueue {
 public:
  explicit JobQueue(ConnectionPool& pool, QueueOptions options = {});

  // Throws std::invalid_argument for an unknown configuration or max_attempts < 1.
  std::int64_t enqueue(const NewJob& job);
  // The same, unless the tenant has `max_active` jobs queued or running already (nullopt then).
  // Count and insert happen under a lock on the tenant's row, so that concurrent submits cannot
  // all pass the count before any of them inserts.
  std::optional<std::int64_t> enqueue_within_limit(const NewJob& job, std::int64_t tenant_id, int max_active);

  // The oldest queued job, now leased to `worker`; nullopt if none is queued.
  std::optional<ClaimedJob> claim(const std::string& worker);
  // Reaps, then claims; if nothing is queued, sleeps until notified (or the poll interval
  // passes) and tries again, until `max_wait` has passed.
  std::optional<ClaimedJob> wait_for_job(const std::string& worker, std::chrono::milliseconds max_wait);

  // Renews the lease. False when the lease is lost (reaped or the job cancelled): stop working.
  bool heartbeat(const Lease& lease);
  // Final states; false (and no change) when the lease is no longer this worker's. A failure
  // reported by the worker is final: retrying the same input would fail the same way.
  bool succeed(const Lease& lease);
  bool fail(const Lease& lease, const std::string& error);
  // Queued or running jobs become cancelled; a running worker learns it at its next heartbeat.
  bool cancel(std::int64_t job_id);

  // Jobs whose lease has expired: re-queued while they have attempts left, else failed with the
  // reason. Returns how many jobs it touched.
  int reap();
  // A worker whose server is stopping gives its job back at once instead of letting the lease
  // run out: re-queued, and allowed one more attempt, since a clean stop is not the job's fault.
  // False when the lease was no longer this worker's.
  bool release(const Lease& lease);
  // A worker that could not finish because the database stayed away longer than its retries,
  // or its scratch disk refused a write (full, failing), gives the job back for another attempt:
  // not the job's fault. Unlike release() the attempt counts, so that a job cannot bounce
  // forever; with none left it fails, saying which. False when the lease was no longer its.
  bool requeue_after_outage(const Lease& lease, Outage outage = Outage::kDatabase);

  bool record_event(const Lease& lease, const std::string& stage, double progress, const std::string& message = "");
  std::vector<JobEvent> events(std::int64_t job_id);
  JobStatus status(std::int64_t job_id);  // throws std::out_of_range for an unknown id

  std::optional<JobRecord> job(std::int64_t job_id);
  // A tenant's jobs, newest first, below `before_id` (0: from the newest): all, or those that
  // join `survey_id` (first or later), or were submitted for `site_id`.
  std::vector<JobRecord> list_jobs(std::int64_t tenant_id, std::optional<std::int64_t> survey_id,
                                   std::int64_t before_id, int limit, std::optional<std::int64_t> site_id = std::nullopt);
  int active_jobs(std::int64_t tenant_id);  // queued or running
  std::vector<StoredJobEvent> events_after(std::int64_t job_id, std::int64_t after_event_id);

 private:
  bool finish(const Lease& lease, JobState state, const std::optional<std::string>& error);

  ConnectionPool& pool_;
  QueueOptions options_;
};

}  // namespace bathyslam::storage
