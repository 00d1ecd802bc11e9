#pragma once
// The server's health as gRPC's health service reports it follows the database: SERVING while
// PostgreSQL answers a query, NOT_SERVING while it does not, so that a load balancer or an
// operator's probe sees a server that could only fail every upload and job.
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <grpcpp/health_check_service_interface.h>

#include "server/storage/database.h"

namespace bathyslam::server {

class DatabaseHealth {
 public:
  // Probes `conninfo` on a connection of its own every `interval` (a pool's connections may all
  // be lent to long jobs) and sets `health`'s status for every service when it changes.
  DatabaseHealth(std::string conninfo, grpc::HealthCheckServiceInterface* health, std::chrono::milliseconds interval);
  DatabaseHealth(const DatabaseHealth&) = delete;
  DatabaseHealth& operator=(const DatabaseHealth&) = delete;
  ~DatabaseHealth();  // stops probing

 private:
  bool answers();  // one probe
  void run();

  std::string conninfo_;
  grpc::HealthCheckServiceInterface* health_;
  std::chrono::milliseconds interval_;
  std::unique_ptr<storage::Connection> connection_;
  bool serving_ = true;  // the server starts only once the database has answered
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace bathyslam::server
