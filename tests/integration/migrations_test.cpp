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

// Migration 0005 gives stored rows what the typed results need: a rejection kind for every
// refused registration (from the words its reason began with), and `gicp` jobs stored parameters
// that still mean what they meant when submitted.
TEST(Migrations, TypedResultsKeepRowsStoredBeforeThem) {
  testing::FreshDatabase db(false);
  Connection connection(db.conninfo());
  std::vector<Migration> up_to_4 = embedded_migrations();
  up_to_4.resize(4);
  migrate(connection, up_to_4);
  connection.exec_script(
      "INSERT INTO tenants (id, name) OVERRIDING SYSTEM VALUE VALUES (1, 't');"
      "INSERT INTO surveys (id, tenant_id, name) OVERRIDING SYSTEM VALUE VALUES (1, 1, 's');"
      "INSERT INTO jobs (id, survey_id, configuration, parameters) OVERRIDING SYSTEM VALUE VALUES"
      " (1, 1, 'gicp', '{\"batch_submaps\": 10, \"robust.dr_gate\": 1, \"gicp.neighbours\": 20}'),"
      " (2, 1, 'mchs', '{\"batch_submaps\": 10, \"robust.dr_gate\": 1}');"
      "INSERT INTO submaps (job_id, idx, line, time_begin, time_mid, time_end, dr_pose, footprint, point_count,"
      " points_encoding, points) SELECT 2, i, 0, 0, 0, 0, '{1,0,0,0,0,0,0}', '((0,0),(1,0),(1,1))', 0, 'f32le', ''"
      " FROM generate_series(0, 1) i;"
      "INSERT INTO constraints (job_id, idx, type, path, from_submap, to_submap, measured, information, converged,"
      " fitness, overlap_points, overlap_mse_m2, overlap_fraction, accepted, reason) SELECT 2, k, 'loop', 'direct', 0,"
      " 1, '{1,0,0,0,0,0,0}', array_fill(0::float8, ARRAY[36]), true, 0, 0, 0, 0, k = 0, r FROM (VALUES"
      " (0, ''), (1, 'inlier ratio 0.21 < 0.25'), (2, 'ambiguous (a second alignment 3.1 m away has 9 of 12)'),"
      " (3, 'ambiguous (the terrain also fits 6.0 m away: distinctness 2.1 < 25.0)'),"
      " (4, 'implausible against dead reckoning (Mahalanobis2 40.1 > 16.3 over 12 submaps)')) v(k, r);");
  migrate(connection);
  auto text = [&](const std::string& sql) { return std::string(connection.exec(sql).text(0, 0)); };
  EXPECT_EQ(text("SELECT string_agg(rejection, '|' ORDER BY idx) FROM constraints"),
            "none|inlier ratio|ambiguous: competing alignment|ambiguous: terrain not unique|"
            "implausible against dead reckoning");
  EXPECT_EQ(text("SELECT parameters->>'batch_submaps' FROM jobs WHERE id = 1"), "0");
  EXPECT_EQ(text("SELECT parameters->>'robust.dr_gate' FROM jobs WHERE id = 1"), "0");
  EXPECT_EQ(text("SELECT parameters->>'gicp.neighbours' FROM jobs WHERE id = 1"), "20");
  EXPECT_EQ(text("SELECT parameters->>'batch_submaps' FROM jobs WHERE id = 2"), "10") << "mchs used them";
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
