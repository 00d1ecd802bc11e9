#include "server/storage/job_queue.h"

#include "core/pipeline/pipeline_config.h"

#include <array>
#include <memory>
#include <stdexcept>
#include <thread>

namespace bathyslam::storage {
namespace {

constexpr std::string_view kChannel = "bathyslam_jobs";
constexpr std::array<std::string_view, 5> kStateNames = {"queued", "running", "succeeded", "failed", "cancelled"};

double seconds(std::chrono::milliseconds duration) { return duration.count() / 1000.0; }

// The lease's identity in every statement that acts on behalf of a worker: $1, $2, $3.
constexpr std::string_view kLeaseHeld = "id = $1 AND worker = $2 AND attempts = $3 AND state = 'running'";

std::string with_lease(std::string_view head, std::string_view tail = "") {
  return std::string(head) + " WHERE " + std::string(kLeaseHeld) + std::string(tail);
}

}  // namespace

bool hold_lease(Connection& connection, const Lease& lease) {
  // KEY SHARE, not SHARE: it conflicts only with the reaper's FOR UPDATE, so the worker's own
  // heartbeats (and a cancel) go on while it stores; under SHARE they waited for the whole
  // transaction, and a store of `large`'s results outlasted the 60 s statement timeout.
  return connection.exec("SELECT 1 FROM jobs WHERE " + std::string(kLeaseHeld) + " FOR KEY SHARE",
                         {lease.job_id, lease.worker, lease.attempt})
             .rows() == 1;
}

LeaseLost::LeaseLost(const Lease& lease)
    : std::runtime_error("job " + std::to_string(lease.job_id) + ": the lease of worker " + lease.worker + " (attempt " +
                         std::to_string(lease.attempt) + ") is no longer held; nothing was written") {}

std::string to_string(JobState state) { return std::string(kStateNames[static_cast<int>(state)]); }

JobState parse_job_state(std::string_view text) {
  for (std::size_t i = 0; i < kStateNames.size(); ++i)
    if (kStateNames[i] == text) return static_cast<JobState>(i);
  throw std::invalid_argument("unknown job state '" + std::string(text) + "'");
}

JobQueue::JobQueue(ConnectionPool& pool, QueueOptions options) : pool_(pool), options_(options) {
  if (options_.lease.count() <= 0 || options_.poll.count() <= 0)
    throw std::invalid_argument("job queue: lease and poll interval must be positive");
}

namespace {

nlohmann::json checked_parameters(const NewJob& job) {
  parse_configuration(job.configuration);  // throws std::invalid_argument naming it
  if (job.max_attempts < 1) throw std::invalid_argument("max_attempts must be at least 1");
  const nlohmann::json parameters = job.parameters.is_null() ? nlohmann::json::object() : job.parameters;
  if (!parameters.is_object()) throw std::invalid_argument("job parameters must be a JSON object");
  return parameters;
}

JobEvent job_event_from(const Result& rows, int row) {
  JobEvent e;
  e.attempt = static_cast<int>(rows.int64(row, "attempt"));
  e.stage = rows.text(row, "stage");
  e.progress = rows.float8(row, "progress");
  e.message = rows.text(row, "message");
  return e;
}

// The tenant's queued and running jobs, on a connection the caller may hold in a transaction.
int active_jobs_of(Connection& connection, std::int64_t tenant_id) {
  return static_cast<int>(connection
                              .exec("SELECT count(*) AS active FROM jobs j JOIN surveys s ON s.id = j.survey_id"
                                    " WHERE s.tenant_id = $1 AND j.state IN ('queued', 'running')",
                                    {tenant_id})
                              .int64(0, "active"));
}

constexpr std::string_view kMoreSurveyIds =
    "coalesce((SELECT string_agg(survey_id::text, ',' ORDER BY position) FROM job_surveys WHERE job_id = j.id), '')"
    " AS more_survey_ids";

// In the caller's transaction when it has one: the job and its other surveys together.
std::int64_t insert_job(Connection& connection, const NewJob& job, const nlohmann::json& parameters) {
  // NOTIFY is delivered at commit, so a woken worker always finds the job.
  const std::int64_t id = connection
                              .exec(
                                  "WITH job AS (INSERT INTO jobs (survey_id, configuration, parameters, max_attempts, site_id)"
                                  " VALUES ($1, $2, $3, $4, $6) RETURNING id)"
                                  " SELECT id, pg_notify($5, id::text) FROM job",
                                  {job.survey_id, job.configuration, parameters.dump(), job.max_attempts, kChannel,
                                   job.site_id})
                              .int64(0, "id");
  for (std::size_t k = 0; k < job.more_survey_ids.size(); ++k) {
    connection.exec("INSERT INTO job_surveys (job_id, position, survey_id) VALUES ($1, $2, $3)",
                    {id, static_cast<std::int64_t>(k + 1), job.more_survey_ids[k]});
  }
  return id;
}

}  // namespace

std::int64_t JobQueue::enqueue(const NewJob& job) {
  const nlohmann::json parameters = checked_parameters(job);
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  const std::int64_t id = insert_job(*connection, job, parameters);
  transaction.commit();
  return id;
}

std::optional<std::int64_t> JobQueue::enqueue_within_limit(const NewJob& job, std::int64_t tenant_id, int max_active) {
  const nlohmann::json parameters = checked_parameters(job);
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  connection->exec("SELECT 1 FROM tenants WHERE id = $1 FOR UPDATE", {tenant_id});
  if (active_jobs_of(*connection, tenant_id) >= max_active) return std::nullopt;
  const std::int64_t id = insert_job(*connection, job, parameters);
  transaction.commit();
  return id;
}

std::optional<ClaimedJob> JobQueue::claim(const std::string& worker) {
  if (worker.empty()) throw std::invalid_argument("a worker needs a name");
  auto connection = pool_.acquire();
  // SKIP LOCKED: concurrent claimers each take a different row instead of queueing on one.
  Result row = connection->exec(
      "UPDATE jobs AS j SET state = 'running', attempts = attempts + 1, worker = $1,"
      " started_at = coalesce(started_at, now()), heartbeat_at = now(),"
      " lease_expires_at = now() + make_interval(secs => $2)"
      " WHERE id = (SELECT id FROM jobs WHERE state = 'queued' ORDER BY id LIMIT 1 FOR UPDATE SKIP LOCKED)"
      " RETURNING id, survey_id, configuration, parameters, attempts, " +
          std::string(kMoreSurveyIds),
      {worker, seconds(options_.lease)});
  if (row.rows() == 0) return std::nullopt;
  ClaimedJob job;
  job.lease.job_id = row.int64(0, "id");
  job.lease.worker = worker;
  job.lease.attempt = static_cast<int>(row.int64(0, "attempts"));
  job.survey_id = row.int64(0, "survey_id");
  job.configuration = row.text(0, "configuration");
  job.parameters = nlohmann::json::parse(row.text(0, "parameters"));
  job.more_survey_ids = parse_id_list(row.text(0, "more_survey_ids"));
  return job;
}

std::optional<ClaimedJob> JobQueue::wait_for_job(const std::string& worker, std::chrono::milliseconds max_wait) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point deadline = Clock::now() + max_wait;
  std::unique_ptr<Connection> listener;  // opened only once the queue turns out empty
  while (true) {
    reap();
    if (auto job = claim(worker)) return job;
    if (!listener && (listener = open_listener(pool_.conninfo(), kChannel))) {
      continue;  // claim once more now that we listen: a job enqueued just before is not missed
    }
    const Clock::time_point now = Clock::now();
    if (now >= deadline) return std::nullopt;
    auto wait = std::min(options_.poll, std::chrono::ceil<std::chrono::milliseconds>(deadline - now));
    if (listener && await_notifications(*listener, wait)) continue;
    // No listener, or it broke (the server restarted): poll this round, listen again next.
    if (!listener) std::this_thread::sleep_for(wait);
    listener.reset();
  }
}

bool JobQueue::heartbeat(const Lease& lease) {
  auto connection = pool_.acquire();
  return connection
             ->exec(with_lease("UPDATE jobs SET heartbeat_at = now(), lease_expires_at = now() + make_interval(secs => $4)"),
                    {lease.job_id, lease.worker, lease.attempt, seconds(options_.lease)})
             .affected() == 1;
}

bool JobQueue::succeed(const Lease& lease) { return finish(lease, JobState::kSucceeded, std::nullopt); }

bool JobQueue::fail(const Lease& lease, const std::string& error) { return finish(lease, JobState::kFailed, error); }

namespace {

// `update` (one job's row) and, when it ended the job, the job's registration checkpoints, in
// one transaction: no attempt will take them up (a kill during the store stage leaves them for
// the next attempt until then). Whether the job ended.
bool end_job(Connection& connection, std::string_view update, std::initializer_list<Param> params, std::int64_t job_id) {
  Transaction transaction(connection);
  const bool ended = connection.exec(update, params).affected() == 1;
  if (ended) connection.exec("DELETE FROM job_checkpoints WHERE job_id = $1", {job_id});
  transaction.commit();
  return ended;
}

}  // namespace

bool JobQueue::finish(const Lease& lease, JobState state, const std::optional<std::string>& error) {
  auto connection = pool_.acquire();
  return end_job(*connection,
                 with_lease("UPDATE jobs SET state = $4, error = $5, finished_at = now(), lease_expires_at = NULL"),
                 {lease.job_id, lease.worker, lease.attempt, to_string(state), error}, lease.job_id);
}

bool JobQueue::cancel(std::int64_t job_id) {
  auto connection = pool_.acquire();
  return end_job(*connection,
                 "UPDATE jobs SET state = 'cancelled', finished_at = now(), lease_expires_at = NULL"
                 " WHERE id = $1 AND state IN ('queued', 'running')",
                 {job_id}, job_id);
}

namespace {

// Running jobs chosen by `where` go back to the queue while `attempts_allowed` (an expression
// over the row, which becomes its max_attempts) is not used up and fail otherwise, with an event
// `stage` saying `what` happened (a format() of the row's worker).
// One statement, so the state change and its event commit together; a job it failed loses its
// checkpoints in the same transaction, by a second statement: its fresh snapshot sees a checkpoint
// that a worker, its lease expired but not yet reaped, committed while the first one ran. Returns
// how many jobs it touched, and notifies waiting workers when one was re-queued.
int requeue_or_fail(Connection& connection, std::string_view where, std::string_view stage, std::string_view what,
                    std::string_view attempts_allowed, const std::vector<Param>& params) {
  Transaction transaction(connection);
  const std::string said = "format('" + std::string(what) + "', worker)";
  const std::string used_up = "attempts >= " + std::string(attempts_allowed);
  Result changed = connection.exec(
      "WITH changed AS ("
      "  UPDATE jobs SET"
      "   max_attempts = " + std::string(attempts_allowed) + ","
      "   state = CASE WHEN " + used_up + " THEN 'failed' ELSE 'queued' END,"
      "   error = CASE WHEN " + used_up + " THEN format('%s on attempt %s of %s; giving up', " + said +
          ", attempts, max_attempts) ELSE error END,"
      "   finished_at = CASE WHEN " + used_up + " THEN now() END,"
      "   lease_expires_at = NULL"
      "  WHERE " + std::string(where) +
          "  RETURNING id, attempts, state, worker"
          "), logged AS ("
          "  INSERT INTO job_events (job_id, attempt, stage, progress, message)"
          "  SELECT id, attempts, '" + std::string(stage) + "', 0, format('%s; %s', " + said +
          ", CASE WHEN state = 'queued' THEN 're-queued' ELSE 'failed' END) FROM changed"
          ")"
          " SELECT count(*) AS changed, count(*) FILTER (WHERE state = 'queued') AS requeued FROM changed",
      params);
  if (changed.int64(0, "changed") > changed.int64(0, "requeued")) {
    connection.exec("DELETE FROM job_checkpoints c USING jobs j WHERE j.id = c.job_id AND j.state = 'failed'");
  }
  if (changed.int64(0, "requeued") > 0) connection.exec("SELECT pg_notify($1, '')", {kChannel});
  transaction.commit();
  return static_cast<int>(changed.int64(0, "changed"));
}

}  // namespace

int JobQueue::reap() {
  auto connection = pool_.acquire();
  // SKIP LOCKED: a row that a heartbeat is renewing right now is not expired after all.
  return requeue_or_fail(*connection,
                         "id IN (SELECT id FROM jobs WHERE state = 'running' AND lease_expires_at < now()"
                         " FOR UPDATE SKIP LOCKED)",
                         "lease-expired", "lease of worker %s expired", "max_attempts", {});
}

bool JobQueue::release(const Lease& lease) {
  auto connection = pool_.acquire();
  // A clean stop is not the job's fault: the attempt it used is given back.
  return requeue_or_fail(*connection, kLeaseHeld, "released", "worker %s stopped with its server", "max_attempts + 1",
                         {lease.job_id, lease.worker, lease.attempt}) == 1;
}

bool JobQueue::requeue_after_outage(const Lease& lease, Outage outage) {
  auto connection = pool_.acquire();
  const std::string_view what = outage == Outage::kDatabase
                                    ? "worker %s lost the database while running it"
                                    : "worker %s could not write its scratch files (disk full or failing)";
  return requeue_or_fail(*connection, kLeaseHeld, "requeued", what, "max_attempts",
                         {lease.job_id, lease.worker, lease.attempt}) == 1;
}

bool JobQueue::record_event(const Lease& lease, const std::string& stage, double progress, const std::string& message) {
  if (!(progress >= 0 && progress <= 1)) throw std::invalid_argument("progress must be within [0, 1]");
  if (stage.empty()) throw std::invalid_argument("an event needs a stage");
  auto connection = pool_.acquire();
  // Only while the lease is held: a worker that lost its job must not write into its history.
  return connection
             ->exec("INSERT INTO job_events (job_id, attempt, stage, progress, message)"
                    " SELECT $1::bigint, $3::integer, $4::text, $5::float8, $6::text FROM jobs WHERE " +
                        std::string(kLeaseHeld),
                    {lease.job_id, lease.worker, lease.attempt, stage, progress, message})
             .affected() == 1;
}

std::vector<JobEvent> JobQueue::events(std::int64_t job_id) {
  auto connection = pool_.acquire();
  Result rows = connection->exec(
      "SELECT attempt, stage, progress, message FROM job_events WHERE job_id = $1 ORDER BY id", {job_id});
  std::vector<JobEvent> events;
  for (int row = 0; row < rows.rows(); ++row) events.push_back(job_event_from(rows, row));
  return events;
}

JobStatus JobQueue::status(std::int64_t job_id) {
  auto connection = pool_.acquire();
  Result row = connection->exec(
      "SELECT id, survey_id, configuration, state, attempts, max_attempts, worker, error FROM jobs WHERE id = $1",
      {job_id});
  if (row.rows() == 0) throw std::out_of_range("no job " + std::to_string(job_id));
  JobStatus status;
  status.id = row.int64(0, "id");
  status.survey_id = row.int64(0, "survey_id");
  status.configuration = row.text(0, "configuration");
  status.state = parse_job_state(row.text(0, "state"));
  status.attempts = static_cast<int>(row.int64(0, "attempts"));
  status.max_attempts = static_cast<int>(row.int64(0, "max_attempts"));
  status.worker = row.optional_text(0, "worker");
  status.error = row.optional_text(0, "error");
  return status;
}

namespace {

const std::string kJobColumns =
    "SELECT j.id, j.survey_id, j.site_id, s.tenant_id, j.configuration, j.state, j.attempts, j.error, j.parameters,"
    " extract(epoch FROM j.created_at)::float8 AS created_at,"
    " coalesce(extract(epoch FROM j.started_at)::float8, 0) AS started_at,"
    " coalesce(extract(epoch FROM j.finished_at)::float8, 0) AS finished_at,"
    " coalesce(e.stage, '') AS stage, coalesce(e.progress, 0) AS progress, " +
    std::string(kMoreSurveyIds) +
    " FROM jobs j JOIN surveys s ON s.id = j.survey_id"
    " LEFT JOIN LATERAL (SELECT stage, progress FROM job_events WHERE job_id = j.id ORDER BY id DESC LIMIT 1) e ON true";

std::vector<JobRecord> job_records(const Result& rows) {
  std::vector<JobRecord> jobs;
  for (int row = 0; row < rows.rows(); ++row) {
    JobRecord job;
    job.id = rows.int64(row, "id");
    job.survey_id = rows.int64(row, "survey_id");
    job.site_id = rows.optional_int64(row, "site_id");
    job.tenant_id = rows.int64(row, "tenant_id");
    job.configuration = rows.text(row, "configuration");
    job.state = parse_job_state(rows.text(row, "state"));
    job.attempts = static_cast<int>(rows.int64(row, "attempts"));
    job.error = rows.optional_text(row, "error");
    job.parameters = nlohmann::json::parse(rows.text(row, "parameters"));
    job.created_at = rows.float8(row, "created_at");
    job.started_at = rows.float8(row, "started_at");
    job.finished_at = rows.float8(row, "finished_at");
    job.stage = rows.text(row, "stage");
    job.progress = rows.float8(row, "progress");
    job.more_survey_ids = parse_id_list(rows.text(row, "more_survey_ids"));
    jobs.push_back(std::move(job));
  }
  return jobs;
}

}  // namespace

std::optional<JobRecord> JobQueue::job(std::int64_t job_id) {
  auto connection = pool_.acquire();
  std::vector<JobRecord> found = job_records(connection->exec(kJobColumns + " WHERE j.id = $1", {job_id}));
  if (found.empty()) return std::nullopt;
  return found.front();
}

std::vector<JobRecord> JobQueue::list_jobs(std::int64_t tenant_id, std::optional<std::int64_t> survey_id,
                                           std::int64_t before_id, int limit, std::optional<std::int64_t> site_id) {
  auto connection = pool_.acquire();
  return job_records(connection->exec(
      kJobColumns +
          " WHERE s.tenant_id = $1 AND ($3::bigint = 0 OR j.id < $3) AND ($5::bigint IS NULL OR j.site_id = $5)"
          " AND ($2::bigint IS NULL OR j.survey_id = $2"
          " OR EXISTS (SELECT 1 FROM job_surveys js WHERE js.job_id = j.id AND js.survey_id = $2))"
          " ORDER BY j.id DESC LIMIT $4",
      {tenant_id, survey_id, before_id, limit, site_id}));
}

int JobQueue::active_jobs(std::int64_t tenant_id) {
  auto connection = pool_.acquire();
  return active_jobs_of(*connection, tenant_id);
}

std::vector<StoredJobEvent> JobQueue::events_after(std::int64_t job_id, std::int64_t after_event_id) {
  auto connection = pool_.acquire();
  Result rows = connection->exec(
      "SELECT id, attempt, stage, progress, message, extract(epoch FROM at)::float8 AS at FROM job_events"
      " WHERE job_id = $1 AND id > $2 ORDER BY id",
      {job_id, after_event_id});
  std::vector<StoredJobEvent> events;
  for (int row = 0; row < rows.rows(); ++row) {
    StoredJobEvent e;
    e.id = rows.int64(row, "id");
    e.event = job_event_from(rows, row);
    e.at = rows.float8(row, "at");
    events.push_back(e);
  }
  return events;
}

}  // namespace bathyslam::storage
