#pragma once
// WatchJob's wake-up call: one LISTEN connection per server on 'bathyslam_job_events' (migration
// 0004 notifies it of every job event and state change, with the job's id) and a count of rings
// per job, so that a watcher sleeps until its job changes instead of polling the database.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>

namespace bathyslam::server {

class JobEventBell {
 public:
  explicit JobEventBell(std::string conninfo);
  ~JobEventBell();  // the listening thread must be gone before the counts it writes
  JobEventBell(const JobEventBell&) = delete;
  JobEventBell& operator=(const JobEventBell&) = delete;

  // How often the job has rung so far; read before looking at the job, then wait() on it.
  std::uint64_t rings(std::int64_t job_id);
  // Sleeps until the job rings past `seen` or `timeout` passes. A notification lost while the
  // LISTEN connection was down costs at most `timeout`.
  void wait(std::int64_t job_id, std::uint64_t seen, std::chrono::milliseconds timeout);

 private:
  void listen();
  void listen_until_stopped();

  std::string conninfo_;
  std::mutex mutex_;
  std::condition_variable rang_;
  std::unordered_map<std::int64_t, std::uint64_t> rings_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace bathyslam::server
