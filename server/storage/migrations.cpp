#include "server/storage/migrations.h"

#include <algorithm>
#include <charconv>
#include <stdexcept>

namespace bathyslam::storage {
namespace {

// Any constant shared by every bathyslam process; "bathyslm" in ASCII.
constexpr std::int64_t kMigrationLock = 0x626174687973'6c6d;

void lock_migrations(Connection& connection) {
  connection.exec("SELECT pg_advisory_xact_lock($1)", {kMigrationLock});
}

}  // namespace

std::vector<Migration> parse_migrations(const std::vector<MigrationFile>& files) {
  std::vector<Migration> migrations;
  for (const MigrationFile& file : files) {
    std::string_view name = file.file_name;
    constexpr std::string_view kSuffix = ".up.sql";
    std::size_t underscore = name.find('_');
    int version = 0;
    auto [end, ec] = std::from_chars(name.data(), name.data() + std::min(underscore, name.size()), version);
    bool well_formed = underscore == 4 && ec == std::errc() && end == name.data() + 4 && version > 0 &&
                       name.ends_with(kSuffix) && name.size() > 4 + 1 + kSuffix.size();
    if (!well_formed)
      throw std::invalid_argument("migration " + std::string(name) + ": expected NNNN_name.up.sql with NNNN >= 0001");
    migrations.push_back({version, std::string(name.substr(5, name.size() - 5 - kSuffix.size())), file.sql});
  }
  std::sort(migrations.begin(), migrations.end(), [](const Migration& a, const Migration& b) { return a.version < b.version; });
  for (std::size_t i = 0; i < migrations.size(); ++i) {
    if (migrations[i].version != static_cast<int>(i) + 1)
      throw std::invalid_argument("migration " + std::to_string(migrations[i].version) + "_" + migrations[i].name +
                                  ": versions must run 1, 2, 3, ... without gaps or repeats");
  }
  return migrations;
}

const std::vector<Migration>& embedded_migrations() {
  static const std::vector<Migration> migrations = parse_migrations(embedded_migration_files());
  return migrations;
}

int schema_version(Connection& connection) {
  Result exists = connection.exec("SELECT to_regclass('schema_migrations') IS NOT NULL AS present");
  if (!exists.boolean(0, "present")) return 0;
  return static_cast<int>(
      connection.exec("SELECT coalesce(max(version), 0) AS version FROM schema_migrations").int64(0, "version"));
}

std::vector<int> migrate(Connection& connection, const std::vector<Migration>& migrations) {
  {
    Transaction transaction(connection);
    lock_migrations(connection);
    connection.exec(
        "CREATE TABLE IF NOT EXISTS schema_migrations ("
        " version integer PRIMARY KEY,"
        " name text NOT NULL,"
        " applied_at timestamptz NOT NULL DEFAULT now())");
    transaction.commit();
  }
  std::vector<int> applied;
  for (const Migration& migration : migrations) {
    Transaction transaction(connection);
    lock_migrations(connection);
    // Re-read under the lock: another process may have applied it while we waited.
    if (schema_version(connection) >= migration.version) continue;
    try {
      connection.exec_script(migration.sql);
    } catch (const DatabaseError& error) {
      throw DatabaseError(error.sqlstate(), std::string("migration ") + std::to_string(migration.version) + "_" +
                                                migration.name + ": " + error.message());
    }
    connection.exec("INSERT INTO schema_migrations (version, name) VALUES ($1, $2)",
                    {migration.version, migration.name});
    transaction.commit();
    applied.push_back(migration.version);
  }
  return applied;
}

void ensure_schema(Connection& connection, bool apply_pending, const std::vector<Migration>& migrations) {
  int current = schema_version(connection);
  int known = migrations.empty() ? 0 : migrations.back().version;
  if (current > known)
    throw SchemaError("the database schema is at version " + std::to_string(current) +
                      ", newer than this server knows (" + std::to_string(known) + "); run a newer bathyslam-server");
  if (current == known) return;
  if (!apply_pending)
    throw SchemaError("the database schema is at version " + std::to_string(current) + ", this server needs " +
                      std::to_string(known) + "; run `bathyslam-server migrate` or start with --migrate");
  migrate(connection, migrations);
}

}  // namespace bathyslam::storage
