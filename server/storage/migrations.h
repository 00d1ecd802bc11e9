#pragma once
// Schema migrations: the numbered files of migrations/ (compiled into the binary), applied in
// order, each in its own transaction, and recorded in schema_migrations.
#include <string>
#include <string_view>
#include <vector>

#include "server/storage/database.h"

namespace bathyslam::storage {

struct MigrationFile {
  std::string_view file_name;  // "0001_init.up.sql"
  std::string_view sql;
};

struct Migration {
  int version = 0;
  std::string name;  // "init"
  std::string_view sql;
};

// migrations/*.up.sql as built into this binary.
const std::vector<MigrationFile>& embedded_migration_files();

// Checks the names ("NNNN_name.up.sql"), numbering (1, 2, 3, ... without gaps or repeats) and
// returns the migrations in version order; throws std::invalid_argument naming the bad file.
std::vector<Migration> parse_migrations(const std::vector<MigrationFile>& files);
const std::vector<Migration>& embedded_migrations();

// 0 for a database that has never been migrated.
int schema_version(Connection& connection);

// Applies every migration newer than the database's version and returns the versions applied
// (none the second time). Concurrent callers (several servers starting at once) serialise on an
// advisory lock, so each migration runs exactly once.
std::vector<int> migrate(Connection& connection, const std::vector<Migration>& migrations = embedded_migrations());

class SchemaError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a server does at start: refuses a schema newer than it knows (an older binary must not
// write into a newer layout), applies pending migrations if `apply_pending`, else refuses them.
void ensure_schema(Connection& connection, bool apply_pending,
                   const std::vector<Migration>& migrations = embedded_migrations());

}  // namespace bathyslam::storage
