#pragma once
// The one door to PostgreSQL: connections, a small pool, transactions and typed, parameterised
// statements. Nothing here builds SQL from values; every value travels as a libpq parameter.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <libpq-fe.h>

namespace bathyslam::storage {

using Bytes = std::vector<std::uint8_t>;

// A failed statement or connection, with PostgreSQL's SQLSTATE ("23505", "08006", ...) so that
// callers can tell a unique violation from a lost connection.
class DatabaseError : public std::runtime_error {
 public:
  DatabaseError(std::string sqlstate, const std::string& message);
  const std::string& sqlstate() const { return sqlstate_; }
  const std::string& message() const { return message_; }  // PostgreSQL's own words
  // The same statement may succeed if tried again later: the connection was lost, the server is
  // shutting down or starting, out of connections, or the transaction lost a serialization race.
  bool transient() const;

 private:
  std::string sqlstate_;
  std::string message_;
};

// One statement parameter. Text for everything PostgreSQL parses itself; binary only for bytea,
// so that blobs are neither escaped nor doubled in size on the way in.
class Param {
 public:
  Param(std::nullopt_t) {}
  Param(const char* text) : value_(text) {}
  Param(std::string_view text) : value_(text_value(std::string(text))) {}
  Param(std::string text) : value_(text_value(std::move(text))) {}
  Param(bool value) : value_(value ? "t" : "f") {}
  Param(double value);
  Param(const Bytes& bytes) : value_(std::string(bytes.begin(), bytes.end())), binary_(true) {}
  template <std::integral T>
    requires(!std::same_as<T, bool>)
  Param(T value) : value_(std::to_string(value)) {}
  template <typename T>
  Param(const std::optional<T>& value) {
    if (value) *this = Param(*value);
  }

  const std::optional<std::string>& value() const { return value_; }
  bool binary() const { return binary_; }

 private:
  // libpq takes text parameters as C strings and would cut one at a NUL byte, silently storing or
  // looking up less than was given: such text throws DatabaseError 22021 (as PostgreSQL refuses
  // a NUL in text). Services refuse it earlier, naming the field; this catches what they miss.
  static std::string text_value(std::string text);

  std::optional<std::string> value_;  // nullopt: SQL NULL
  bool binary_ = false;
};

// A double[] literal ("{1,0.5,...}") in shortest exact form, so arrays of poses and
// information matrices round-trip bit for bit.
std::string float8_array(const double* values, std::size_t count);
std::vector<double> parse_float8_array(std::string_view text);
// Ids as string_agg(id::text, ',') gives them ("" for none).
std::vector<std::int64_t> parse_id_list(std::string_view list);

// Owns a PGresult; cells are read as text (PostgreSQL's text output of float8 is exact).
class Result {
 public:
  explicit Result(PGresult* result) : result_(result, &PQclear) {}
  int rows() const { return PQntuples(result_.get()); }
  int affected() const;  // rows changed by INSERT/UPDATE/DELETE
  bool is_null(int row, int column) const { return PQgetisnull(result_.get(), row, column) == 1; }
  // The index of a column by its name, so that a row mapper does not depend on the SELECT's
  // order; throws DatabaseError naming the column when the result has none of that name.
  int column(const char* name) const;
  std::string_view text(int row, int column) const;
  std::int64_t int64(int row, int column) const;
  double float8(int row, int column) const;
  bool boolean(int row, int column) const;
  Bytes bytes(int row, int column) const;  // a bytea column, in either result format
  std::optional<std::int64_t> optional_int64(int row, int column) const;
  std::optional<std::string> optional_text(int row, int column) const;
  // The same cells by column name, as storage reads them: a reader then depends neither on the
  // order of its SELECT nor on a struct's field order.
  bool is_null(int row, const char* name) const { return is_null(row, column(name)); }
  std::string_view text(int row, const char* name) const { return text(row, column(name)); }
  std::int64_t int64(int row, const char* name) const { return int64(row, column(name)); }
  double float8(int row, const char* name) const { return float8(row, column(name)); }
  bool boolean(int row, const char* name) const { return boolean(row, column(name)); }
  Bytes bytes(int row, const char* name) const { return bytes(row, column(name)); }
  std::optional<std::int64_t> optional_int64(int row, const char* name) const { return optional_int64(row, column(name)); }
  std::optional<std::string> optional_text(int row, const char* name) const { return optional_text(row, column(name)); }

 private:
  std::unique_ptr<PGresult, decltype(&PQclear)> result_;
};

class Connection {
 public:
  // `statement_timeout` (0: PostgreSQL's default, none) ends any statement that runs longer,
  // with SQLSTATE 57014; a connection string that sets its own options keeps them.
  explicit Connection(const std::string& conninfo, std::chrono::milliseconds statement_timeout = {});
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  // Runs one parameterised statement; throws DatabaseError on any failure.
  Result exec(std::string_view sql, std::initializer_list<Param> params = {});
  Result exec(std::string_view sql, const std::vector<Param>& params);
  // As exec, every column of the result in PostgreSQL's binary format: for statements that
  // select only bytea columns (read with Result::bytes), which then come without hex to decode
  // and at half the bytes.
  Result exec_binary(std::string_view sql, const std::vector<Param>& params);
  // COPY ... FROM STDIN with `data` as its input (in the statement's format); throws
  // DatabaseError on any failure. PostgreSQL's fastest way in for many rows or large values.
  void copy_in(std::string_view copy_statement, std::string_view data);
  // Several statements in one string, no parameters: for migration files only (trusted SQL).
  void exec_script(std::string_view sql);

  // A server restart or a terminated backend leaves a connection that looks fine until used.
  // Reads whatever the server sent meanwhile and reconnects if the connection turned out dead.
  void ensure_alive();
  bool in_transaction() const;

  PGconn* raw() { return conn_.get(); }

 private:
  Result run(std::string_view sql, const std::vector<Param>& params, int result_format);

  std::unique_ptr<PGconn, decltype(&PQfinish)> conn_;
};

class ConnectionPool;

// A connection borrowed from a pool, given back when it goes out of scope.
class PooledConnection {
 public:
  PooledConnection(ConnectionPool* pool, std::unique_ptr<Connection> connection)
      : pool_(pool), connection_(std::move(connection)) {}
  PooledConnection(PooledConnection&&) = default;
  PooledConnection& operator=(PooledConnection&&) = delete;
  ~PooledConnection();
  Connection& operator*() { return *connection_; }
  Connection* operator->() { return connection_.get(); }

 private:
  ConnectionPool* pool_;
  std::unique_ptr<Connection> connection_;
};

struct PoolOptions {
  // No statement of a request or a job needs minutes; one that does is stuck on a lock or a
  // runaway plan, and holds a connection every other caller needs.
  std::chrono::milliseconds statement_timeout{60'000};
  // How long acquire() waits for a connection to come back when all are lent out.
  std::chrono::milliseconds acquire_timeout{10'000};
};

// A few connections shared by threads. Connections open lazily, up to `size`; acquire() waits
// for one to come back when all are lent out, up to `acquire_timeout`, and then throws a
// DatabaseError with SQLSTATE 53300 (too many connections: transient, so callers may retry).
class ConnectionPool {
 public:
  ConnectionPool(std::string conninfo, std::size_t size, PoolOptions options = {});
  PooledConnection acquire();
  const std::string& conninfo() const { return conninfo_; }

 private:
  friend class PooledConnection;
  void release(std::unique_ptr<Connection> connection);

  std::string conninfo_;
  std::size_t size_;
  PoolOptions options_;
  std::size_t opened_ = 0;
  std::vector<std::unique_ptr<Connection>> idle_;
  std::mutex mutex_;
  std::condition_variable returned_;
};

// A connection of its own that LISTENs on `channel` (a constant identifier); nullptr when it
// cannot be opened (the caller polls instead).
std::unique_ptr<Connection> open_listener(const std::string& conninfo, std::string_view channel);
// Sleeps until notifications arrive on a listening connection or `timeout` passes; their
// payloads (none after a timeout), or nullopt when the connection broke.
std::optional<std::vector<std::string>> await_notifications(Connection& connection, std::chrono::milliseconds timeout);

// BEGIN now, ROLLBACK on scope exit unless commit() was called: an exception anywhere between
// leaves the database as it was.
class Transaction {
 public:
  explicit Transaction(Connection& connection);
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  ~Transaction();
  void commit();
  Connection& connection() { return connection_; }

 private:
  Connection& connection_;
  bool done_ = false;
};

}  // namespace bathyslam::storage
