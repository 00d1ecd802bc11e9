// Migrations: applied once, in order, each atomically; the server's start-up check.
#include <thread>

#include <gtest/gtest.h>

#include "server/storage/migrations.h"
#include "tests/integration/fresh_database.h"

namespace bathyslam::storage {
namespace {

int latest() { return embedded_migrations().back().version; }

TEST(Migrations, ApplyOnAnEmptyDatabaseThenAreANoOp) {
  testing::FreshDatabase db(false);
  Connection connection(db.conninfo());
  EXPECT_EQ(schema_version(connection), 0);
  std::vector<int> applied = migrate(connection);
  ASSERT_EQ(static_cast<int>(applied.size()), latest());
  EXPECT_EQ(schema_version(connection), latest());
  EXPECT_EQ(db.scalar("SELECT count(*) FROM information_schema.tables WHERE table_name = 'jobs'"), 1);
  const long long tables = db.scalar("SELECT count(*) FROM information_schema.tables WHERE table_schema = 'public'");

  EXPECT_TRUE(migrate(connection).empty());
  EXPECT_EQ(schema_version(connection), latest());
  EXPECT_EQ(db.scalar("SELECT count(*) FROM schema_migrations"), latest());
  EXPECT_EQ(db.scalar("SELECT count(*) FROM information_schema.tables WHERE table_schema = 'public'"), tables);
}

TEST(Migrations, ConcurrentMigratorsApplyEachMigrationOnce) {
  testing::FreshDatabase db(false);
  std::vector<int> applied[2];
  std::thread threads[2];
  for (int i = 0; i < 2; ++i)
    threads[i] = std::thread([&, i] {
      Connection connection(db.conninfo());
      applied[i] = migrate(connection);
    });
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(static_cast<int>(applied[0].size() + applied[1].size()), latest());
  EXPECT_EQ(db.scalar("SELECT count(*) FROM schema_migrations"), latest());
}

TEST(Migrations, AFailingMigrationLeavesOnlyTheEarlierOnes) {
  testing::FreshDatabase db(false);
  Connection connection(db.conninfo());
  const std::vector<MigrationFile> files = {
      {"0001_a.up.sql", "CREATE TABLE a (id int);"},
      {"0002_b.up.sql", "CREATE TABLE b (id int); INSERT INTO b VALUES ('not a number');"},
  };
  try {
    migrate(connection, parse_migrations(files));
    FAIL() << "a broken migration applied";
  } catch (const DatabaseError& error) {
    EXPECT_EQ(error.sqlstate(), "22P02");
    EXPECT_NE(std::string(error.what()).find("migration 2_b"), std::string::npos) << error.what();
  }
  EXPECT_EQ(schema_version(connection), 1);
  EXPECT_EQ(db.scalar("SELECT count(*) FROM information_schema.tables WHERE table_name = 'a'"), 1);
  EXPECT_EQ(db.scalar("SELECT count(*) FROM information_schema.tables WHERE table_name = 'b'"), 0);
}

TEST(Migrations, FileNamesAndNumberingAreChecked) {
  EXPECT_THROW(parse_migrations({{"1_init.up.sql", ""}}), std::invalid_argument);
  EXPECT_THROW(parse_migrations({{"0001_init.sql", ""}}), std::invalid_argument);
  EXPECT_THROW(parse_migrations({{"0001_.up.sql", ""}}), std::invalid_argument);
  EXPECT_THROW(parse_migrations({{"0001_a.up.sql", ""}, {"0003_c.up.sql", ""}}), std::invalid_argument);
  EXPECT_THROW(parse_migrations({{"0001_a.up.sql", ""}, {"0001_b.up.sql", ""}}), std::invalid_argument);
  std::vector<Migration> ok = parse_migrations({{"0002_b.up.sql", "B"}, {"0001_a.up.sql", "A"}});
  ASSERT_EQ(ok.size(), 2u);
  EXPECT_EQ(ok[0].name, "a");
  EXPECT_EQ(ok[1].sql, "B");
}

TEST(Migrations, StartUpRefusesANewerSchemaAndPendingOnesUnlessAsked) {
  testing::FreshDatabase db(false);
  Connection connection(db.conninfo());
  EXPECT_THROW(ensure_schema(connection, false), SchemaError);
  EXPECT_EQ(schema_version(connection), 0);
  ensure_schema(connection, true);
  EXPECT_EQ(schema_version(connection), latest());
  ensure_schema(connection, false);  // up to date: fine

  connection.exec("INSERT INTO schema_migrations (version, name) VALUES ($1, 'from the future')", {latest() + 1});
  try {
    ensure_schema(connection, true);
    FAIL() << "started on a newer schema";
  } catch (const SchemaError& error) {
    EXPECT_NE(std::string(error.what()).find("newer"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace bathyslam::storage
