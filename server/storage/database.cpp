#include "server/storage/database.h"

#include <poll.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>

namespace bathyslam::storage {
namespace {

std::string shortest(double value) {
  // PostgreSQL spells the special values its own way.
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "Infinity" : "-Infinity";
  char buffer[32];
  auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, end);
}

double parse_double(std::string_view text) {
  if (text == "NaN") return std::nan("");
  if (text == "Infinity") return INFINITY;
  if (text == "-Infinity") return -INFINITY;
  double value = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size())
    throw DatabaseError("XX000", "not a number from the database: '" + std::string(text) + "'");
  return value;
}

std::string connection_message(PGconn* conn) {
  std::string message = conn ? PQerrorMessage(conn) : "out of memory";
  while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) message.pop_back();
  return message;
}

// Connection failures have no SQLSTATE of their own; 08006 is "connection failure".
DatabaseError connection_error(PGconn* conn) { return DatabaseError("08006", connection_message(conn)); }

}  // namespace

DatabaseError::DatabaseError(std::string sqlstate, const std::string& message)
    : std::runtime_error("database error " + sqlstate + ": " + message), sqlstate_(std::move(sqlstate)),
      message_(message) {}

bool DatabaseError::transient() const {
  const std::string_view state = sqlstate_;
  return state.starts_with("08")                                          // connection exception
         || state.starts_with("53")                                       // insufficient resources
         || state == "57P01" || state == "57P02" || state == "57P03"      // shutdown, cannot connect now
         || state == "40001" || state == "40P01";                         // serialization failure, deadlock
}

Param::Param(double value) : value_(shortest(value)) {}

std::string Param::text_value(std::string text) {
  if (text.find('\0') != std::string::npos)
    throw DatabaseError("22021", "a text parameter holds a NUL byte, which libpq would cut it at");
  return text;
}

std::string float8_array(const double* values, std::size_t count) {
  std::string text = "{";
  for (std::size_t i = 0; i < count; ++i) {
    if (i) text += ',';
    text += shortest(values[i]);
  }
  return text + "}";
}

std::vector<std::int64_t> parse_id_list(std::string_view list) {
  std::vector<std::int64_t> ids;
  while (!list.empty()) {
    const std::size_t comma = std::min(list.find(','), list.size());
    ids.push_back(std::stoll(std::string(list.substr(0, comma))));
    list.remove_prefix(std::min(comma + 1, list.size()));
  }
  return ids;
}

std::vector<double> parse_float8_array(std::string_view text) {
  if (text.size() < 2 || text.front() != '{' || text.back() != '}')
    throw DatabaseError("XX000", "not a float8 array: '" + std::string(text) + "'");
  std::vector<double> values;
  text = text.substr(1, text.size() - 2);
  while (!text.empty()) {
    std::size_t comma = text.find(',');
    values.push_back(parse_double(text.substr(0, comma)));
    if (comma == std::string_view::npos) break;
    text.remove_prefix(comma + 1);
  }
  return values;
}

int Result::affected() const {
  const char* count = PQcmdTuples(result_.get());
  return *count ? std::atoi(count) : 0;
}

int Result::column(const char* name) const {
  const int index = PQfnumber(result_.get(), name);
  if (index < 0) throw DatabaseError("42703", std::string("the result has no column '") + name + "'");
  return index;
}

std::string_view Result::text(int row, int column) const {
  return {PQgetvalue(result_.get(), row, column),
          static_cast<std::size_t>(PQgetlength(result_.get(), row, column))};
}

std::int64_t Result::int64(int row, int column) const {
  std::string_view cell = text(row, column);
  std::int64_t value = 0;
  auto [end, ec] = std::from_chars(cell.data(), cell.data() + cell.size(), value);
  if (ec != std::errc() || end != cell.data() + cell.size())
    throw DatabaseError("XX000", "not an integer from the database: '" + std::string(cell) + "'");
  return value;
}

double Result::float8(int row, int column) const { return parse_double(text(row, column)); }

bool Result::boolean(int row, int column) const { return text(row, column) == "t"; }

Bytes Result::bytes(int row, int column) const {
  if (PQfformat(result_.get(), column) == 1) {
    const auto* raw = reinterpret_cast<const unsigned char*>(PQgetvalue(result_.get(), row, column));
    return Bytes(raw, raw + PQgetlength(result_.get(), row, column));
  }
  std::size_t length = 0;
  unsigned char* raw = PQunescapeBytea(reinterpret_cast<const unsigned char*>(PQgetvalue(result_.get(), row, column)),
                                       &length);
  if (!raw) throw DatabaseError("XX000", "cannot decode a bytea value");
  Bytes bytes(raw, raw + length);
  PQfreemem(raw);
  return bytes;
}

std::optional<std::int64_t> Result::optional_int64(int row, int column) const {
  if (is_null(row, column)) return std::nullopt;
  return int64(row, column);
}

std::optional<std::string> Result::optional_text(int row, int column) const {
  if (is_null(row, column)) return std::nullopt;
  return std::string(text(row, column));
}

namespace {

// A connection string with a default connect_timeout of 10 s, which the string's own overrides:
// without one, a database host that drops packets holds a worker, or the health probe, for
// minutes of TCP retries. The statement timeout goes the same way, as a default server option.
PGconn* connect_with_timeout(const std::string& conninfo, std::chrono::milliseconds statement_timeout) {
  const std::string options = "-c statement_timeout=" + std::to_string(statement_timeout.count());
  const char* keywords[] = {"connect_timeout", "options", "dbname", nullptr};
  const char* values[] = {"10", statement_timeout.count() > 0 ? options.c_str() : "", conninfo.c_str(), nullptr};
  return PQconnectdbParams(keywords, values, /*expand_dbname=*/1);
}

}  // namespace

Connection::Connection(const std::string& conninfo, std::chrono::milliseconds statement_timeout)
    : conn_(connect_with_timeout(conninfo, statement_timeout), &PQfinish) {
  if (!conn_ || PQstatus(conn_.get()) != CONNECTION_OK) throw connection_error(conn_.get());
  // Server notices (e.g. "relation already exists, skipping") are not errors; keep stderr clean.
  PQsetNoticeProcessor(conn_.get(), [](void*, const char*) {}, nullptr);
}

static Result checked(PGconn* conn, PGresult* raw) {
  Result result(raw);
  if (!raw) throw connection_error(conn);
  ExecStatusType status = PQresultStatus(raw);
  if (status == PGRES_COMMAND_OK || status == PGRES_TUPLES_OK) return result;
  const char* sqlstate = PQresultErrorField(raw, PG_DIAG_SQLSTATE);
  std::string message = PQresultErrorMessage(raw);
  while (!message.empty() && message.back() == '\n') message.pop_back();
  throw DatabaseError(sqlstate ? sqlstate : "08006", message.empty() ? connection_message(conn) : message);
}

Result Connection::exec(std::string_view sql, std::initializer_list<Param> params) {
  return exec(sql, std::vector<Param>(params));
}

Result Connection::exec(std::string_view sql, const std::vector<Param>& params) { return run(sql, params, 0); }

Result Connection::exec_binary(std::string_view sql, const std::vector<Param>& params) { return run(sql, params, 1); }

Result Connection::run(std::string_view sql, const std::vector<Param>& params, int result_format) {
  std::vector<const char*> values;
  std::vector<int> lengths, formats;
  for (const Param& param : params) {
    values.push_back(param.value() ? param.value()->data() : nullptr);
    lengths.push_back(param.value() ? static_cast<int>(param.value()->size()) : 0);
    formats.push_back(param.binary() ? 1 : 0);
  }
  std::string statement(sql);
  return checked(conn_.get(), PQexecParams(conn_.get(), statement.c_str(), static_cast<int>(params.size()),
                                           nullptr, values.data(), lengths.data(), formats.data(), result_format));
}

void Connection::copy_in(std::string_view copy_statement, std::string_view data) {
  std::string statement(copy_statement);
  PGresult* started = PQexec(conn_.get(), statement.c_str());
  if (started == nullptr || PQresultStatus(started) != PGRES_COPY_IN) {
    checked(conn_.get(), started);  // throws the server's reason
    throw DatabaseError("08P01", "not a COPY FROM STDIN: " + statement);
  }
  PQclear(started);
  constexpr std::size_t kPiece = 1 << 20;
  for (std::size_t at = 0; at < data.size(); at += kPiece) {
    const std::size_t n = std::min(kPiece, data.size() - at);
    if (PQputCopyData(conn_.get(), data.data() + at, static_cast<int>(n)) != 1) throw connection_error(conn_.get());
  }
  if (PQputCopyEnd(conn_.get(), nullptr) != 1) throw connection_error(conn_.get());
  // The COPY's own result, then the end of results.
  for (PGresult* raw; (raw = PQgetResult(conn_.get())) != nullptr;) checked(conn_.get(), raw);
}

void Connection::exec_script(std::string_view sql) {
  std::string script(sql);
  checked(conn_.get(), PQexec(conn_.get(), script.c_str()));
}

void Connection::ensure_alive() {
  // An idle connection has nothing to read unless the server is going away: a terminated
  // backend sends its FATAL message and then closes. Reading until nothing is readable reaches
  // that end of file, which is what makes libpq mark the connection bad.
  pollfd readable{PQsocket(conn_.get()), POLLIN, 0};
  for (int round = 0; round < 8 && PQstatus(conn_.get()) == CONNECTION_OK; ++round) {
    if (readable.fd < 0 || poll(&readable, 1, 0) <= 0 || !PQconsumeInput(conn_.get())) break;
    PQisBusy(conn_.get());  // parses what was read (notices go to the silent notice processor)
  }
  if (PQstatus(conn_.get()) == CONNECTION_OK) return;
  PQreset(conn_.get());
  if (PQstatus(conn_.get()) != CONNECTION_OK) throw connection_error(conn_.get());
}

std::unique_ptr<Connection> open_listener(const std::string& conninfo, std::string_view channel) {
  try {
    auto connection = std::make_unique<Connection>(conninfo);
    connection->exec("LISTEN " + std::string(channel));
    return connection;
  } catch (const DatabaseError&) {
    return nullptr;
  }
}

std::optional<std::vector<std::string>> await_notifications(Connection& connection, std::chrono::milliseconds timeout) {
  pollfd descriptor{PQsocket(connection.raw()), POLLIN, 0};
  if (descriptor.fd < 0) return std::nullopt;
  if (poll(&descriptor, 1, static_cast<int>(timeout.count())) < 0) return std::nullopt;
  if (!PQconsumeInput(connection.raw())) return std::nullopt;
  std::vector<std::string> payloads;
  while (PGnotify* notification = PQnotifies(connection.raw())) {
    payloads.emplace_back(notification->extra);
    PQfreemem(notification);
  }
  if (PQstatus(connection.raw()) != CONNECTION_OK) return std::nullopt;
  return payloads;
}

bool Connection::in_transaction() const { return PQtransactionStatus(conn_.get()) != PQTRANS_IDLE; }

PooledConnection::~PooledConnection() {
  if (connection_) pool_->release(std::move(connection_));
}

ConnectionPool::ConnectionPool(std::string conninfo, std::size_t size, PoolOptions options)
    : conninfo_(std::move(conninfo)), size_(size), options_(options) {
  if (size_ == 0) throw std::invalid_argument("connection pool: size must be at least 1");
  // Fail at start, not at the first request, when the database is unreachable.
  release(std::make_unique<Connection>(conninfo_, options_.statement_timeout));
  opened_ = 1;
}

PooledConnection ConnectionPool::acquire() {
  std::unique_ptr<Connection> connection;
  {
    std::unique_lock lock(mutex_);
    if (!returned_.wait_for(lock, options_.acquire_timeout, [&] { return !idle_.empty() || opened_ < size_; }))
      throw DatabaseError("53300", "no database connection came free within " +
                                       std::to_string(options_.acquire_timeout.count()) + " ms (all " +
                                       std::to_string(size_) + " of the pool are in use)");
    if (!idle_.empty()) {
      connection = std::move(idle_.back());
      idle_.pop_back();
    } else {
      ++opened_;
    }
  }
  try {
    if (connection) {
      connection->ensure_alive();
    } else {
      connection = std::make_unique<Connection>(conninfo_, options_.statement_timeout);
    }
  } catch (...) {
    std::lock_guard lock(mutex_);
    if (!connection) --opened_;  // a connection that never opened frees its slot
    else idle_.push_back(std::move(connection));
    returned_.notify_one();
    throw;
  }
  return PooledConnection(this, std::move(connection));
}

void ConnectionPool::release(std::unique_ptr<Connection> connection) {
  // A connection returned mid-transaction (an exception escaped before the rollback ran) must not
  // carry that transaction to its next user.
  if (connection->in_transaction() && PQstatus(connection->raw()) == CONNECTION_OK) {
    try {
      connection->exec("ROLLBACK");
    } catch (const DatabaseError&) {
    }
  }
  std::lock_guard lock(mutex_);
  idle_.push_back(std::move(connection));
  returned_.notify_one();
}

Transaction::Transaction(Connection& connection) : connection_(connection) { connection_.exec("BEGIN"); }

Transaction::~Transaction() {
  if (done_) return;
  try {
    connection_.exec("ROLLBACK");
  } catch (const DatabaseError&) {
    // The connection is gone; the server has rolled the transaction back already.
  }
}

void Transaction::commit() {
  connection_.exec("COMMIT");
  done_ = true;
}

}  // namespace bathyslam::storage
