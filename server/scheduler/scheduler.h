#pragma once
// The scheduler: a pool of job workers, each claiming jobs from the queue, running the core
// pipeline with the remaining cores, and storing what it produced. While a job runs, a watcher
// polls its state (a cancelled job stops within a fraction of a second of the poll) and renews
// the lease.
#include <atomic>
#include <chrono>
#include <functional>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/pipeline/registration_checkpoint.h"
#include "core/products/difference_products.h"
#include "server/scheduler/map_products.h"
#include "server/scheduler/retry.h"
#include "server/storage/job_queue.h"
#include "server/storage/result_store.h"
#include "server/storage/survey_store.h"

namespace bathyslam::server {

struct SchedulerOptions {
  int workers = 1;
  std::string name = "bathyslam";                  // workers are "<name>/<index>"
  std::filesystem::path scratch;                   // bundles are parsed from copies here
  std::chrono::milliseconds state_poll{200};       // how soon a cancellation is noticed
  std::chrono::milliseconds heartbeat{5'000};      // well within the queue's lease
  std::chrono::milliseconds progress_every{500};   // at most one progress event per stage this often
  RetryPolicy retry;                               // storing results through a database outage
  std::uint64_t max_map_cells = 100'000'000;       // a larger map is refused before fusion
};

class Scheduler {
 public:
  Scheduler(storage::SurveyStore& surveys, storage::JobQueue& jobs, storage::ResultStore& results,
            SchedulerOptions options);
  ~Scheduler();  // stop()
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  void start();
  // Stops claiming and interrupts running jobs, which go back to the queue for another server
  // (or this one, restarted) to run again.
  void stop();

 private:
  void work(const std::string& worker);
  void run(const storage::ClaimedJob& job);
  // `failed_products`: the optional products not written, [{product, reason}], for the report.
  // The differences of a job of several surveys: each written in `dir` (difference_products.h).
  struct SiteDifferences {
    std::filesystem::path dir;
    std::vector<DifferenceProducts> products;
  };
  void store(const storage::ClaimedJob& job, const PipelineResult& result, const MapProducts& map,
             const std::vector<std::filesystem::path>& corrected_gsfs, const SiteDifferences& differences,
             const nlohmann::json& failed_products,
             const std::function<void(const char*, double)>& event, const std::atomic<bool>& cancel);
  // What an earlier attempt of the job registered, and where this attempt keeps what it registers.
  RegistrationCheckpoints checkpoints(const storage::Lease& lease, const std::atomic<bool>& cancel);
  void release(const storage::Lease& lease, double seconds);
  void requeue_after_outage(const storage::Lease& lease, double seconds, const std::string& error,
                            storage::Outage outage);
  void fail(const storage::Lease& lease, double seconds, const std::string& error);
  void withdraw_if_cancelled(std::int64_t job_id);

  storage::SurveyStore& surveys_;
  storage::JobQueue& jobs_;
  storage::ResultStore& results_;
  SchedulerOptions options_;
  std::atomic<bool> stopping_{false};
  std::vector<std::thread> threads_;
};

}  // namespace bathyslam::server
