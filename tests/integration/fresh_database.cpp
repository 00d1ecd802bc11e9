#include "tests/integration/fresh_database.h"

#include <unistd.h>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include <gtest/gtest.h>

#include "server/storage/migrations.h"

namespace bathyslam::testing {
namespace {

std::string quoted_identifier(storage::Connection& connection, const std::string& name) {
  char* quoted = PQescapeIdentifier(connection.raw(), name.c_str(), name.size());
  if (!quoted) throw std::runtime_error("cannot quote " + name);
  std::string result(quoted);
  PQfreemem(quoted);
  return result;
}

}  // namespace

std::string required_env(const char* name) {
  const char* value = std::getenv(name);
  if (!value || !*value)
    throw std::runtime_error(std::string(name) + " is not set: run these tests through ctest, which starts the cluster");
  return value;
}

std::string socket_conninfo(const std::string& cluster_dir, const std::string& database) {
  // The socket directory through any symlink: socket paths must stay short.
  const std::string socket_dir = (std::filesystem::canonical(cluster_dir) / "run").string();
  return "host=" + socket_dir + " user=postgres dbname=" + database;
}

std::string cluster_conninfo(const std::string& database) {
  return socket_conninfo(required_env("BATHYSLAM_TEST_PG"), database);
}

FreshDatabase::FreshDatabase(bool migrated) {
  const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string base = test ? std::string(test->test_suite_name()) + "_" + test->name() : "adhoc";
  for (char& c : base) c = std::isalnum(static_cast<unsigned char>(c)) ? static_cast<char>(std::tolower(c)) : '_';
  name_ = "t_" + base.substr(0, 40) + "_" + std::to_string(getpid());
  storage::Connection admin(cluster_conninfo());
  const std::string quoted = quoted_identifier(admin, name_);
  admin.exec("DROP DATABASE IF EXISTS " + quoted + " WITH (FORCE)");
  admin.exec("CREATE DATABASE " + quoted);
  conninfo_ = cluster_conninfo(name_);
  if (migrated) {
    storage::Connection connection(conninfo_);
    storage::migrate(connection);
  }
}

FreshDatabase::~FreshDatabase() {
  try {
    storage::Connection admin(cluster_conninfo());
    admin.exec("DROP DATABASE IF EXISTS " + quoted_identifier(admin, name_) + " WITH (FORCE)");
  } catch (const std::exception& error) {
    ADD_FAILURE() << "cannot drop " << name_ << ": " << error.what();
  }
}

long long FreshDatabase::scalar(const std::string& sql) {
  storage::Connection connection(conninfo_);
  return connection.exec(sql).int64(0, 0);
}

}  // namespace bathyslam::testing
