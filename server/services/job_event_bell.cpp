#include "server/services/job_event_bell.h"

#include <charconv>

#include "server/log.h"
#include "server/storage/database.h"

namespace bathyslam::server {
namespace {

constexpr std::string_view kChannel = "bathyslam_job_events";
// How long one wait on the socket lasts: how soon the destructor is noticed.
constexpr auto kListenSlice = std::chrono::milliseconds(200);

}  // namespace

JobEventBell::JobEventBell(std::string conninfo) : conninfo_(std::move(conninfo)), thread_([this] { listen(); }) {}

JobEventBell::~JobEventBell() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  thread_.join();
}

std::uint64_t JobEventBell::rings(std::int64_t job_id) {
  std::lock_guard lock(mutex_);
  const auto found = rings_.find(job_id);
  return listens_ + (found == rings_.end() ? 0 : found->second);
}

bool JobEventBell::wait(std::int64_t job_id, std::uint64_t seen, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  const bool moved = rang_.wait_for(lock, timeout, [&] {
    const auto found = rings_.find(job_id);
    return stopping_ || listens_ + (found == rings_.end() ? 0 : found->second) > seen;
  });
  return moved || !listening_;
}

void JobEventBell::set_listening(bool listening) {
  {
    std::lock_guard lock(mutex_);
    if (listening && !listening_) ++listens_;
    listening_ = listening;
  }
  rang_.notify_all();
}

void JobEventBell::listen() {
  try {
    listen_until_stopped();
  } catch (const std::exception& error) {  // an exception leaving a thread ends the process
    log("job events: listening stopped (%s); watchers fall back to polling", error.what());
  } catch (...) {
    log("job events: listening stopped; watchers fall back to polling");
  }
  set_listening(false);
}

void JobEventBell::listen_until_stopped() {
  std::unique_ptr<storage::Connection> connection;
  bool reported = false;
  while (true) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_) break;
    }
    if (!connection) {
      if (!(connection = storage::open_listener(conninfo_, kChannel))) {
        if (!reported) log("job events: cannot LISTEN; watchers fall back to polling");
        reported = true;
        std::this_thread::sleep_for(std::chrono::seconds(1));
        continue;
      }
      set_listening(true);  // wakes every watcher: what rang while it did not listen went unheard
    }
    reported = false;
    const auto payloads = storage::await_notifications(*connection, kListenSlice);
    if (!payloads) {
      set_listening(false);  // watchers poll until the database is back and it listens again
      connection.reset();
      continue;
    }
    if (payloads->empty()) continue;
    {
      std::lock_guard lock(mutex_);
      for (const std::string& payload : *payloads) {
        std::int64_t job_id = 0;
        if (std::from_chars(payload.data(), payload.data() + payload.size(), job_id).ec == std::errc()) ++rings_[job_id];
      }
    }
    rang_.notify_all();
  }
}

}  // namespace bathyslam::server
