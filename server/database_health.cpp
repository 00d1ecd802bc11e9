#include "server/database_health.h"

#include "server/log.h"

namespace bathyslam::server {

DatabaseHealth::DatabaseHealth(std::string conninfo, grpc::HealthCheckServiceInterface* health,
                               std::chrono::milliseconds interval)
    : conninfo_(std::move(conninfo)), health_(health), interval_(interval), thread_([this] { run(); }) {}

DatabaseHealth::~DatabaseHealth() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

bool DatabaseHealth::answers() {
  try {
    if (connection_) {
      connection_->ensure_alive();
    } else {
      connection_ = std::make_unique<storage::Connection>(conninfo_);
    }
    connection_->exec("SELECT 1");
    return true;
  } catch (const std::exception& error) {
    if (serving_) log("database unreachable, health NOT_SERVING: %s", error.what());
    return false;
  } catch (...) {  // nothing may leave the probing thread
    if (serving_) log("database unreachable, health NOT_SERVING: unknown error");
    return false;
  }
}

void DatabaseHealth::run() {
  std::unique_lock lock(mutex_);
  while (!wake_.wait_for(lock, interval_, [this] { return stopping_; })) {
    lock.unlock();
    const bool serving = answers();
    lock.lock();
    if (serving == serving_ || stopping_) continue;
    serving_ = serving;
    health_->SetServingStatus(serving);
    if (serving) log("database reachable again, health SERVING");
  }
}

}  // namespace bathyslam::server
