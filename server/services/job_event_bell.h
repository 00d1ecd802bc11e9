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

  // A count that moves when the job rings, and when the bell starts listening (again: what
  // rang meanwhile went unheard); read before looking at the job, then wait() on it.
  std::uint64_t rings(std::int64_t job_id);
  // Sleeps until the count moves past `seen` (true: look at the job again) or `timeout` passes.
  // Then true only while the bell is not listening, so that a watcher polls; false while it
  // listens: nothing changed, and a watcher need not read the database, however many there are.
  bool wait(std::int64_t job_id, std::uint64_t seen, std::chrono::milliseconds timeout);

 private:
  void listen();
  void listen_until_stopped();
  void set_listening(bool listening);

  std::string conninfo_;
  std::mutex mutex_;
  std::condition_variable rang_;
  std::unordered_map<std::int64_t, std::uint64_t> rings_;
  bool listening_ = false;
  std::uint64_t listens_ = 0;  // how often it started listening: a term of every job's count
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace bathyslam::server
