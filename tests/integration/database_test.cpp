// The libpq layer itself: parameters, errors, transactions, and the pool's reconnect.
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>

#include <gtest/gtest.h>

#include "server/storage/database.h"
#include "tests/integration/fresh_database.h"

namespace bathyslam::storage {
namespace {

TEST(Database, DoublesRoundTripExactlyIncludingSpecialValues) {
  testing::FreshDatabase db(false);
  Connection connection(db.conninfo());
  const double values[] = {0.1, -1e-300, 1.0 / 3.0, 4.63e6 + 0.123456789, std::numeric_limits<double>::max(),
                           std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (double value : values) {
    Result row = connection.exec("SELECT $1::float8", {value});
    EXPECT_EQ(row.float8(0, 0), value);
  }
  EXPECT_TRUE(std::isnan(connection.exec("SELECT $1::float8", {std::nan("")}).float8(0, 0)));
  const double array[] = {1e-17, -2.5, 123456.789012345};
  std::vector<double> back =
      parse_float8_array(connection.exec("SELECT $1::float8[]", {float8_array(array, 3)}).text(0, 0));
  EXPECT_EQ(back, std::vector<double>(array, array + 3));
}

TEST(Database, ValuesTravelAsParametersNeverAsSql) {
  testing::FreshDatabase db(false);
  Connection connection(db.conninfo());
  connection.exec("CREATE TABLE t (name text, blob bytea)");
  const std::string hostile = "x'); DROP TABLE t; --";
  const Bytes blob = {0, 1, 2, 0xff, 0, 'a'};
  connection.exec("INSERT INTO t VALUES ($1, $2)", {hostile, blob});
  Result row = connection.exec("SELECT name, blob FROM t");
  ASSERT_EQ(row.rows(), 1);
  EXPECT_EQ(row.text(0, 0), hostile);
  EXPECT_EQ(row.bytes(0, 1), blob);
  EXPECT_TRUE(row.is_null(0, 0) == false);
  EXPECT_TRUE(connection.exec("SELECT $1::text IS NULL", {std::nullopt}).boolean(0, 0));
}

// libpq would cut "nav.csv\0x" to "nav.csv": text with a NUL never reaches it.
TEST(Database, TextWithANulByteIsRefusedNotCut) {
  testing::FreshDatabase db(false);
  Connection connection(db.conninfo());
  const std::string cut("nav.csv\0x", 9);
  try {
    connection.exec("SELECT $1::text", {cut});
    FAIL() << "text with a NUL byte was sent";
  } catch (const DatabaseError& error) {
    EXPECT_EQ(error.sqlstate(), "22021");
  }
  EXPECT_EQ(connection.exec("SELECT length($1::bytea)", {Bytes(cut.begin(), cut.end())}).int64(0, 0), 9);  // bytea carries NULs
}

TEST(Database, ErrorsCarryTheSqlState) {
  testing::FreshDatabase db(false);
  Connection connection(db.conninfo());
  connection.exec("CREATE TABLE t (id int PRIMARY KEY)");
  connection.exec("INSERT INTO t VALUES (1)");
  try {
    connection.exec("INSERT INTO t VALUES ($1)", {1});
    FAIL() << "duplicate key accepted";
  } catch (const DatabaseError& error) {
    EXPECT_EQ(error.sqlstate(), "23505");
    EXPECT_NE(std::string(error.what()).find("duplicate key"), std::string::npos) << error.what();
  }
  EXPECT_THROW(Connection("host=/nonexistent-socket-dir user=postgres"), DatabaseError);
}

TEST(Database, TransactionRollsBackUnlessCommitted) {
  testing::FreshDatabase db(false);
  Connection connection(db.conninfo());
  connection.exec("CREATE TABLE t (id int)");
  try {
    Transaction transaction(connection);
    connection.exec("INSERT INTO t VALUES (1)");
    throw std::runtime_error("halfway");
  } catch (const std::runtime_error&) {
  }
  {
    Transaction transaction(connection);
    connection.exec("INSERT INTO t VALUES (2)");
    transaction.commit();
  }
  EXPECT_EQ(connection.exec("SELECT string_agg(id::text, ',') FROM t").text(0, 0), "2");
  EXPECT_FALSE(connection.in_transaction());
}

TEST(Database, PoolReconnectsAfterItsBackendIsKilled) {
  testing::FreshDatabase db(false);
  ConnectionPool pool(db.conninfo(), 1);
  std::int64_t pid = pool.acquire()->exec("SELECT pg_backend_pid()").int64(0, 0);
  // What a server restart does to every idle pooled connection, done to just this one.
  Connection admin(db.conninfo());
  ASSERT_TRUE(admin.exec("SELECT pg_terminate_backend($1::int, 5000)", {pid}).boolean(0, 0));
  auto connection = pool.acquire();
  std::int64_t new_pid = connection->exec("SELECT pg_backend_pid()").int64(0, 0);
  EXPECT_NE(new_pid, pid);
}

TEST(Database, PoolReconnectsAfterTheServerRestarts) {
  // A cluster of its own: restarting the shared one would break the tests running beside this.
  const std::string script = BATHYSLAM_PG_SH;
  const std::string dir = testing::required_env("BATHYSLAM_TEST_PG") + "-restart-" + std::to_string(getpid());
  auto pg = [&](const std::string& command) {
    return std::system(("bash " + script + " " + command + " " + dir + " > /dev/null").c_str());
  };
  ASSERT_EQ(pg("start"), 0);
  struct Destroy {
    std::function<int(const std::string&)> pg;
    ~Destroy() { pg("destroy"); }
  } destroy{pg};
  ConnectionPool pool(testing::socket_conninfo(dir), 2);
  {
    auto a = pool.acquire();
    auto b = pool.acquire();  // two connections now idle in the pool when the server goes
    a->exec("SELECT 1");
    b->exec("SELECT 1");
  }
  ASSERT_EQ(pg("stop"), 0);
  try {
    pool.acquire()->exec("SELECT 1");
    FAIL() << "a query while the server is down";
  } catch (const DatabaseError& error) {
    EXPECT_EQ(error.sqlstate(), "08006") << error.what();
  }
  ASSERT_EQ(pg("start"), 0);
  auto a = pool.acquire();
  auto b = pool.acquire();
  EXPECT_EQ(a->exec("SELECT 41 + 1").int64(0, 0), 42);
  EXPECT_EQ(b->exec("SELECT 41 + 1").int64(0, 0), 42);
}

TEST(Database, PoolLendsEachConnectionToOneBorrowerAtATime) {
  testing::FreshDatabase db(false);
  ConnectionPool pool(db.conninfo(), 2);
  auto a = pool.acquire();
  auto b = pool.acquire();
  EXPECT_NE(a->exec("SELECT pg_backend_pid()").int64(0, 0), b->exec("SELECT pg_backend_pid()").int64(0, 0));
  std::int64_t pid_a = a->exec("SELECT pg_backend_pid()").int64(0, 0);
  // A connection given back mid-transaction is rolled back before its next borrower sees it.
  a->exec("BEGIN");
  a->exec("CREATE TABLE leaked (id int)");
  { auto gone = std::move(a); }
  auto c = pool.acquire();
  EXPECT_EQ(c->exec("SELECT pg_backend_pid()").int64(0, 0), pid_a);
  EXPECT_FALSE(c->exec("SELECT to_regclass('leaked') IS NOT NULL").boolean(0, 0));
}

TEST(Database, AStatementRunningPastTheTimeoutIsCancelled) {
  testing::FreshDatabase db(false);
  ConnectionPool pool(db.conninfo(), 1, {.statement_timeout = std::chrono::milliseconds(300)});
  auto connection = pool.acquire();
  const auto start = std::chrono::steady_clock::now();
  try {
    connection->exec("SELECT pg_sleep(5)");
    FAIL() << "a 5 s statement ran to its end";
  } catch (const DatabaseError& error) {
    EXPECT_EQ(error.sqlstate(), "57014");  // query_canceled
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));
  EXPECT_EQ(connection->exec("SELECT 1").int64(0, 0), 1);  // the connection is still good
  // A connection string's own setting wins over the pool's default.
  ConnectionPool own(db.conninfo() + " options='-c statement_timeout=0'", 1,
                     {.statement_timeout = std::chrono::milliseconds(300)});
  EXPECT_EQ(own.acquire()->exec("SHOW statement_timeout").text(0, 0), "0");
}

TEST(Database, AWaitForAPooledConnectionIsBounded) {
  testing::FreshDatabase db(false);
  ConnectionPool pool(db.conninfo(), 1, {.acquire_timeout = std::chrono::milliseconds(300)});
  auto held = pool.acquire();
  const auto start = std::chrono::steady_clock::now();
  try {
    pool.acquire();
    FAIL() << "a second connection out of a pool of one";
  } catch (const DatabaseError& error) {
    EXPECT_EQ(error.sqlstate(), "53300");
    EXPECT_TRUE(error.transient());
  }
  const auto waited = std::chrono::steady_clock::now() - start;
  EXPECT_GE(waited, std::chrono::milliseconds(300));
  EXPECT_LT(waited, std::chrono::seconds(2));
  { auto given_back = std::move(held); }
  EXPECT_EQ(pool.acquire()->exec("SELECT 1").int64(0, 0), 1);
}

}  // namespace
}  // namespace bathyslam::storage
