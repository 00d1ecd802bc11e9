#include "server/scheduler/scheduler.h"

#include <algorithm>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <optional>

#include "core/io/file_bytes.h"
#include "core/pipeline/job_input.h"
#include "core/pipeline/parameters.h"
#include "core/pipeline/pipeline.h"
#include "core/pipeline/report.h"
#include "core/products/corrected_gsf.h"
#include "server/log.h"
#include "server/scheduler/map_products.h"
#include "server/scheduler/retry.h"
#include "server/scratch_dir.h"
#include "server/storage/stored_bundle.h"

namespace bathyslam::server {
namespace {

namespace storage = bathyslam::storage;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Watches a running job from its own thread: sets `cancel` when the job is no longer this
// worker's (cancelled, deleted, lease reaped) or the server stops, and renews the lease. Nothing
// it meets ends the thread (an exception escaping a thread ends the process): while the
// database is away it keeps the job running and the lease decides.
class JobWatcher {
 public:
  JobWatcher(storage::JobQueue& jobs, const storage::Lease& lease, const SchedulerOptions& options,
             const std::atomic<bool>& stopping, std::atomic<bool>& cancel)
      : thread_([&, lease] {
          const std::string job = "job " + std::to_string(lease.job_id);
          FailureStreak poll(job + ": state poll"), heartbeat(job + ": heartbeat");
          auto last_heartbeat = Clock::now();
          std::unique_lock lock(mutex_);
          while (!done_) {
            if (stopping || !still_ours(jobs, lease, poll)) {
              cancel = true;
            } else if (Clock::now() - last_heartbeat >= options.heartbeat) {
              try {
                if (!jobs.heartbeat(lease)) cancel = true;
                heartbeat.succeeded();
                last_heartbeat = Clock::now();
              } catch (const std::exception& error) {
                heartbeat.failed(error.what());  // tried again at the next poll
              }
            }
            wake_.wait_for(lock, options.state_poll);
          }
        }) {}
  ~JobWatcher() {
    {
      std::lock_guard lock(mutex_);
      done_ = true;
    }
    wake_.notify_one();
    thread_.join();
  }

 private:
  static bool still_ours(storage::JobQueue& jobs, const storage::Lease& lease, FailureStreak& poll) {
    try {
      const storage::JobStatus status = jobs.status(lease.job_id);
      poll.succeeded();
      return status.state == storage::JobState::kRunning && status.worker == lease.worker && status.attempts == lease.attempt;
    } catch (const std::out_of_range&) {
      return false;  // deleted with its survey
    } catch (const std::exception& error) {
      poll.failed(error.what());
      return true;  // the database may come back; the lease decides
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  bool done_ = false;
  std::thread thread_;
};

// The job's stored parameters (every parameter, by name) applied to a fresh config.
PipelineConfig job_config(const storage::ClaimedJob& job, int threads) {
  PipelineConfig config = configuration_of(job.configuration, job.parameters.get<std::map<std::string, double>>());
  if (config.threads == 0) config.threads = threads;
  return config;
}

storage::Report report_with_plots(const PipelineResult& result, const std::filesystem::path& scratch_root) {
  const ScratchDir dir(scratch_root, "report");
  storage::Report report{report_json(result), {}};
  write_report_plots(result, dir.path());
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    std::ifstream in(entry.path(), std::ios::binary);
    report.plots[entry.path().filename().string()] =
        storage::Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  return report;
}

// Writes an optional product with `write`: nullopt when written, else why not, in words for the
// user (the scratch folder `dir` left out of them). A survey the product cannot hold (a ping of
// more beams than GSF's 2-byte field) must not take the job's map down with it. A disk fault is
// no such reason (WriteError: the job is given back), nor is a database outage or a cancel.
std::optional<std::string> optional_product(const std::filesystem::path& dir, const std::function<void()>& write) {
  try {
    write();
    return std::nullopt;
  } catch (const WriteError&) {
    throw;
  } catch (const Cancelled&) {
    throw;
  } catch (const storage::DatabaseError&) {
    throw;  // the survey read again while the database is away: the job's to retry, not a product's failure
  } catch (const std::exception& error) {
    return without_folder(error.what(), dir);
  }
}

}  // namespace

Scheduler::Scheduler(storage::SurveyStore& surveys, storage::JobQueue& jobs, storage::ResultStore& results,
                     SchedulerOptions options)
    : surveys_(surveys), jobs_(jobs), results_(results), options_(std::move(options)) {
  if (options_.workers < 0) throw std::invalid_argument("--workers must not be negative");
}

Scheduler::~Scheduler() { stop(); }

void Scheduler::start() {
  for (int i = 0; i < options_.workers; ++i)
    threads_.emplace_back([this, worker = options_.name + "/" + std::to_string(i)] { work(worker); });
}

void Scheduler::stop() {
  stopping_ = true;
  for (std::thread& thread : threads_) thread.join();
  threads_.clear();
}

void Scheduler::work(const std::string& worker) {
  while (!stopping_) {
    try {
      // A short wait, so that stop() is never kept waiting long.
      if (auto job = jobs_.wait_for_job(worker, std::chrono::seconds(1))) run(*job);
    } catch (const std::exception& error) {
      log("%s: %s; retrying in 1 s", worker.c_str(), error.what());
      sleep_unless(stopping_, std::chrono::seconds(1));
    } catch (...) {
      log("%s: unknown exception; retrying in 1 s", worker.c_str());
      sleep_unless(stopping_, std::chrono::seconds(1));
    }
  }
}

// Gives the job back to the queue, so that another server (or this one, restarted) runs it now
// rather than when the lease would have expired.
void Scheduler::release(const storage::Lease& lease, double seconds) {
  const long long id = lease.job_id;
  try {
    if (jobs_.release(lease)) log("job %lld: stopped after %.1f s with the server; given back to the queue", id, seconds);
    else log("job %lld: stopped after %.1f s with the server; no longer ours", id, seconds);
  } catch (const std::exception& error) {
    log("job %lld: stopped after %.1f s with the server; could not give it back (%s), its lease will expire", id,
        seconds, error.what());
  }
}

// Gives the job back after the database stayed away longer than the retries; if even that
// cannot reach the database, the lease expires and the reaper of any server re-queues it.
// The same when the scratch disk refused a write: the job's input is not at fault, so it is not
// failed for it.
void Scheduler::requeue_after_outage(const storage::Lease& lease, double seconds, const std::string& error,
                                     storage::Outage outage) {
  const long long id = lease.job_id;
  const char* what = outage == storage::Outage::kDatabase ? "database unavailable" : "scratch disk failed";
  try {
    if (jobs_.requeue_after_outage(lease, outage))
      log("job %lld: %s after %.1f s (%s); given back to the queue", id, what, seconds, error.c_str());
    else log("job %lld: %s after %.1f s (%s); no longer ours", id, what, seconds, error.c_str());
  } catch (const std::exception& again) {
    log("job %lld: %s after %.1f s (%s); its lease will expire", id, what, seconds, again.what());
  }
}

// What each stage produced, in the order of the pipeline. Everything an earlier try stored is
// discarded first, so that the whole sequence can run again after a transient failure.
void Scheduler::store(const storage::ClaimedJob& job, const PipelineResult& result, const MapProducts& map,
                      const std::vector<std::filesystem::path>& corrected_gsfs, const SiteDifferences& differences,
                      const nlohmann::json& failed_products,
                      const std::function<void(const char*, double)>& event, const std::atomic<bool>& cancel) {
  const std::int64_t id = job.lease.job_id;
  storage::ResultStore results = results_.fenced(job.lease);  // nothing lands once the lease is lost
  constexpr int kStores = 6;
  int stored = 0;
  auto step = [&](const char* what, const std::function<void()>& save) {
    if (cancel) throw Cancelled();
    event(what, static_cast<double>(stored++) / kStores);
    save();
  };
  step("submaps", [&] {
    results.discard(id);  // whatever an earlier attempt or try stored before it was stopped
    results.save_origin(id, result.submaps.origin);
    results.save_submaps(id, result.submaps.submaps);
  });
  step("constraints", [&] { results.save_constraints(id, result.constraints); });
  step("optimized poses", [&] { results.save_optimized_poses(id, result.optimized_poses); });
  step("tiles", [&] {
    for (const auto& [key, bytes] : map.tiles) results.put_tile(id, key, bytes);
    if (map.grid.levels > 0) results.save_map_grid(id, map.grid);
  });
  step("corrected GSF", [&] {
    for (const std::filesystem::path& gsf : corrected_gsfs) results.put_file(id, gsf.filename().string(), gsf);
    for (const DifferenceProducts& d : differences.products) {
      if (d.map.cells_compared > 0) results.put_file(id, d.stem + ".tif", differences.dir / (d.stem + ".tif"));
    }
  });
  step("report", [&] {
    storage::Report report = report_with_plots(result, options_.scratch);
    report.report["failed_products"] = failed_products;
    if (!differences.products.empty()) {
      nlohmann::json& list = report.report["site"]["differences"] = nlohmann::json::array();
      for (const DifferenceProducts& d : differences.products) list.push_back(d.summary);
    }
    report.plots.insert(map.plots.begin(), map.plots.end());
    results.save_report(id, report);
  });
}

// Jobs that resume (docs/service.md): the batches an earlier attempt stored are taken up where
// they are still this run's (the pipeline checks each against its candidates and their guesses);
// bytes this build cannot read are registered again. Each batch registered is stored under the
// lease as it comes: a lost lease stops the job there, a failed write costs only that checkpoint.
RegistrationCheckpoints Scheduler::checkpoints(const storage::Lease& lease, const std::atomic<bool>& cancel) {
  const long long id = lease.job_id;
  const std::string name = "job " + std::to_string(id);
  RegistrationCheckpoints checkpoints;
  const std::vector<storage::Bytes> stored = retry_transient(name + ": loading its checkpoints", options_.retry, cancel,
                                                             [&] { return results_.load_checkpoints(id); });
  for (const storage::Bytes& bytes : stored) {
    try {
      checkpoints.stored.push_back(batch_from_checkpoint(bytes));
    } catch (const CheckpointError& error) {
      log("job %lld: a stored checkpoint is not read (%s); its batch is registered again", id, error.what());
    }
  }
  // After a failed write the next ones wait 10 s: a database that does not answer would otherwise
  // hold the registrations up to its connect timeout every batch.
  checkpoints.keep = [this, lease, streak = FailureStreak(name + ": storing a checkpoint"),
                      next_try = Clock::time_point{}](const RegisteredBatch& batch) mutable {
    if (Clock::now() < next_try) return;
    try {
      results_.fenced(lease).save_checkpoint(lease.job_id, batch.begin, batch.end, checkpoint_bytes(batch));
      streak.succeeded();
    } catch (const storage::DatabaseError& error) {  // a checkpoint is a cache: the job goes on
      streak.failed(error.what());
      next_try = Clock::now() + std::chrono::seconds(10);
    }
  };
  return checkpoints;
}

void Scheduler::run(const storage::ClaimedJob& job) {
  const storage::Lease& lease = job.lease;
  const long long id = lease.job_id;
  const std::string name = "job " + std::to_string(id);
  const auto start = Clock::now();
  log("job %lld: claimed by %s (attempt %d): survey %lld, %s", id, lease.worker.c_str(), lease.attempt,
      static_cast<long long>(job.survey_id), job.configuration.c_str());
  std::atomic<bool> cancel{false};
  JobWatcher watcher(jobs_, lease, options_, stopping_, cancel);
  // Progress events are for watchers: one lost while the database is away costs nothing, and
  // an exception must not leave the progress callback (the pipeline calls it mid-stage).
  FailureStreak events(name + ": progress events");
  auto event = [&](const std::string& stage, double progress, const std::string& message = "") noexcept {
    try {
      jobs_.record_event(lease, stage, std::clamp(progress, 0.0, 1.0), message);
      events.succeeded();
    } catch (const std::exception& error) {
      events.failed(error.what());
    }
  };
  bool succeeded = false;
  try {
    // Registrations share the machine's cores among the workers.
    const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    const PipelineConfig config = job_config(job, std::max(1, cores / std::max(1, options_.workers)));
    event("load", 0);
    // Its surveys: one, or several of one site joined in one graph (the first is the datum).
    std::vector<std::int64_t> survey_ids = {job.survey_id};
    survey_ids.insert(survey_ids.end(), job.more_survey_ids.begin(), job.more_survey_ids.end());
    std::vector<std::optional<storage::StoredSurvey>> files(survey_ids.size());
    auto stored = [&](std::size_t k) -> const storage::StoredSurvey& {
      if (!files[k]) files[k].emplace(surveys_, survey_ids[k], options_.scratch);
      return *files[k];
    };
    std::vector<SurveyReader> reads;
    std::vector<std::string> names;
    for (std::size_t k = 0; k < survey_ids.size(); ++k) {
      names.push_back("survey " + std::to_string(survey_ids[k]));
      reads.push_back([&, k](PingSink& sink) {
        BundleReadResult bundle = stored(k).read(sink);
        if (!bundle.survey) throw BundleError(std::move(bundle.problems));
        return std::move(*bundle.survey);
      });
    }
    // The map's extent: Finalize checked it too; a survey finalized before the limit existed is
    // checked here.
    const FuseConfig fuse{.resolution_m = 0, .max_cells = options_.max_map_cells};
    std::vector<Survey> site;
    // A bundle streams from the database: an outage while it is read starts the reading again
    // (the pings went into submaps that cannot be taken back), and costs a retry, not the attempt.
    JobInput input = retry_transient(name + ": loading its surveys", options_.retry, cancel, [&] {
      site.clear();
      return survey_ids.size() == 1 ? read_job_input(reads.front(), config, fuse)
                                    : read_site_input(reads, names, config, fuse, site);
    });
    // The surveys are read again for their corrected GSF, one at a time: the later ones' scratch
    // copies of sonar files go now (a site's together could fill the scratch disk) and are made
    // again then.
    for (std::size_t k = 1; k < files.size(); ++k) files[k].reset();
    const Survey& survey = input.survey;
    event("load", 1, std::to_string(input.pings) + " pings");

    const RegistrationCheckpoints checkpoints = this->checkpoints(lease, cancel);
    // Progress: every stage change, and within a stage at most every `progress_every`.
    std::string last_stage;
    auto last_event = Clock::now();
    PipelineResult result = run_pipeline(
        std::move(input.submaps), input.read_seconds, config,
        [&](std::string_view stage, double fraction) {
          if (stage == "done") return;  // the job is done once its results are stored
          if (stage == last_stage && fraction < 1 && Clock::now() - last_event < options_.progress_every) return;
          last_stage = stage;
          last_event = Clock::now();
          event(std::string(stage), fraction);
        },
        &cancel, &checkpoints);
    if (result.batches_taken_up > 0)
      log("job %lld: took up %d of %d registered batches from an earlier attempt", id, result.batches_taken_up,
          result.batches);
    if (!job.more_survey_ids.empty()) event("change", 0, "registrations across surveys over a change of the seabed");
    discount_change_across_surveys(result, input.fuse, DifferenceConfig{});
    throw_if_cancelled(&cancel);

    event("map", 0, "fusing and tiling");
    const MapProducts map = make_map_products(result, survey.metadata, input.fuse, options_.scratch);
    event("map", 0.5, "writing the corrected GSF");
    const ScratchDir gsf_dir(options_.scratch, "gsf");
    // Each corrected GSF stays a file (it can be as large as the upload) until stored chunk by chunk.
    std::vector<std::filesystem::path> gsfs;
    nlohmann::json failed_products = nlohmann::json::array();
    for (std::size_t k = 0; k < survey_ids.size() && input.pings > 0; ++k) {
      throw_if_cancelled(&cancel);
      const std::filesystem::path path = gsf_dir.path() / corrected_gsf_name(static_cast<int>(k) + 1);
      // A database outage while the survey is read again is the job's to retry, not a failed
      // product: the file is written again from its start.
      if (auto failure = optional_product(gsf_dir.path(), [&] {
            retry_transient(name + ": writing " + path.filename().string(), options_.retry, cancel, [&] {
              write_corrected_gsf(k == 0 ? survey : site[k], result, path,
                                  [&](PingSink& sink) { return stored(k).read(sink); }, static_cast<int>(k));
            });
          })) {
        const std::string product = path.filename().string();
        log("job %lld: %s not written: %s", id, product.c_str(), failure->c_str());
        event("map", 0.75, product + " not written: " + *failure);
        failed_products.push_back({{"product", product}, {"reason", *failure}});
      } else {
        gsfs.push_back(path);
      }
      if (k > 0) files[k].reset();
    }
    // The change between surveys (difference_pairs): difference_J_K.tif stored as a file, its
    // JSON in the report.
    const ScratchDir difference_dir(options_.scratch, "difference");
    std::vector<DifferenceProducts> differences;
    for (const auto& [before, after] : difference_pairs(static_cast<int>(survey_ids.size()))) {
      throw_if_cancelled(&cancel);
      // As the corrected GSF: a difference that cannot be written is reported, the map stands.
      if (auto failure = optional_product(difference_dir.path(), [&] {
            differences.push_back(write_difference_products(result, survey.metadata, input.fuse, before, after,
                                                            DifferenceConfig{}, difference_dir.path()));
          })) {
        const std::string product = "difference_" + std::to_string(before + 1) + "_" + std::to_string(after + 1);
        log("job %lld: %s not written: %s", id, product.c_str(), failure->c_str());
        failed_products.push_back({{"product", product}, {"reason", *failure}});
      }
    }
    retry_transient(name + ": storing results", options_.retry, cancel, [&] {
      store(job, result, map, gsfs, {difference_dir.path(), differences}, failed_products,
            [&](const char* what, double progress) { event("store", progress, what); }, cancel);
    });
    event("done", 1);
    succeeded = retry_transient(name + ": marking it succeeded", options_.retry, cancel, [&] { return jobs_.succeed(lease); });
    if (succeeded) log("job %lld: succeeded in %.1f s", id, seconds_since(start));
    else log("job %lld: finished in %.1f s but the lease was lost (cancelled or reaped)", id, seconds_since(start));
  } catch (const storage::LeaseLost& error) {
    log("job %lld: stopped after %.1f s: %s", id, seconds_since(start), error.what());
  } catch (const Cancelled&) {
    if (stopping_) {
      release(lease, seconds_since(start));
    } else {
      log("job %lld: stopped after %.1f s (cancelled or no longer ours)", id, seconds_since(start));
    }
  } catch (const storage::DatabaseError& error) {
    if (stopping_) release(lease, seconds_since(start));
    else if (error.transient()) requeue_after_outage(lease, seconds_since(start), error.what(), storage::Outage::kDatabase);
    else fail(lease, seconds_since(start), error.what());
  } catch (const WriteError& error) {
    if (stopping_) release(lease, seconds_since(start));
    else requeue_after_outage(lease, seconds_since(start), error.what(), storage::Outage::kScratchDisk);
  } catch (const std::exception& error) {
    if (stopping_) {
      release(lease, seconds_since(start));
    } else if (cancel) {
      log("job %lld: stopped after %.1f s: %s", id, seconds_since(start), error.what());
    } else {
      fail(lease, seconds_since(start), error.what());
    }
  }
  if (!succeeded) withdraw_if_cancelled(id);
}

// A cancel may land between two store steps or after the last one (the steps' FOR KEY SHARE
// lets it through), and is final all the same: what the job stored is removed. Only a cancelled
// job's: one whose lease was reaped keeps its rows for its next attempt to discard. Should the
// database be away, the rows stay, and the map RPCs refuse a cancelled job's.
void Scheduler::withdraw_if_cancelled(std::int64_t job_id) {
  const long long id = job_id;
  try {
    if (results_.discard_if_cancelled(job_id)) log("job %lld: cancelled; whatever it had stored is removed", id);
  } catch (const std::exception& error) {
    log("job %lld: could not remove what it stored before it was cancelled (%s); never served", id, error.what());
  }
}

// A failure of the job itself (its input, its parameters): final, since the same input would
// fail the same way. Recording it retries through a short outage; after that the lease expires.
void Scheduler::fail(const storage::Lease& lease, double seconds, const std::string& error) {
  log("job %lld: failed after %.1f s: %s", static_cast<long long>(lease.job_id), seconds, error.c_str());
  try {
    retry_transient("job " + std::to_string(lease.job_id) + ": recording its failure", options_.retry, stopping_,
                    [&] { return jobs_.fail(lease, error); });
  } catch (const std::exception& again) {
    log("job %lld: could not record the failure (%s); its lease will expire", static_cast<long long>(lease.job_id),
        again.what());
  }
}

}  // namespace bathyslam::server
