#pragma once
// Every test gets a database of its own in the private cluster that ctest starts
// (scripts/pg.sh, fixture `pg`), so tests run in parallel without seeing each other's rows.
#include <string>

#include "server/storage/database.h"

namespace bathyslam::testing {

// The cluster's admin connection string, from BATHYSLAM_TEST_PG (the cluster's directory).
// Fails the test loudly when it is missing: a storage test that silently skips proves nothing.
std::string cluster_conninfo(const std::string& database = "postgres");
// The same for any cluster made by scripts/pg.sh in `cluster_dir`.
std::string socket_conninfo(const std::string& cluster_dir, const std::string& database = "postgres");
// An environment variable that ctest sets; throws when it is missing.
std::string required_env(const char* name);

class FreshDatabase {
 public:
  // An empty database named after the running test; with `migrated`, at the latest schema.
  explicit FreshDatabase(bool migrated = true);
  ~FreshDatabase();
  FreshDatabase(const FreshDatabase&) = delete;
  FreshDatabase& operator=(const FreshDatabase&) = delete;

  const std::string& conninfo() const { return conninfo_; }
  const std::string& name() const { return name_; }
  // One number from a query (row counts in assertions).
  long long scalar(const std::string& sql);

 private:
  std::string name_;
  std::string conninfo_;
};

}  // namespace bathyslam::testing
