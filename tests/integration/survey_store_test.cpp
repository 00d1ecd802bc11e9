// Surveys, their files and tenants' tokens.
#include <gtest/gtest.h>

#include <fstream>

#include "core/io/file_bytes.h"
#include "server/storage/survey_store.h"
#include "tests/integration/fresh_database.h"

namespace bathyslam::storage {
namespace {

Bytes bytes_of(const std::string& text) { return Bytes(text.begin(), text.end()); }

long long rows_under_surveys(testing::FreshDatabase& db) {
  return db.scalar("SELECT (SELECT count(*) FROM surveys) + (SELECT count(*) FROM survey_files)"
                   " + (SELECT count(*) FROM survey_file_chunks)");
}

TEST(SurveyStore, FilesAreChunkedAndReassembledWithTheirHash) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool, 7);  // tiny chunks, so that every file spans several
  const std::int64_t tenant = store.create_tenant("acme");
  const Bytes nav = bytes_of("time,easting,northing,depth,roll,pitch,heading\n1,2,3,4,5,6,7\n");
  const Bytes empty;
  const std::int64_t survey = store.create_survey(tenant, "lake", {{"nav.csv", nav}, {"empty.txt", empty}});

  std::vector<StoredFile> files = store.files(survey);
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[1].name, "nav.csv");
  EXPECT_EQ(files[1].size_bytes, static_cast<std::int64_t>(nav.size()));
  EXPECT_EQ(files[1].chunk_count, static_cast<int>((nav.size() + 6) / 7));
  EXPECT_EQ(files[1].sha256, sha256(nav));
  EXPECT_EQ(files[0].chunk_count, 0);
  EXPECT_EQ(hex(sha256(empty)), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(store.read_file(survey, "nav.csv"), nav);
  EXPECT_EQ(store.read_file(survey, "empty.txt"), empty);
  EXPECT_THROW(store.read_file(survey, "pings.csv"), std::out_of_range);

  // Storage that no longer matches the upload is noticed, not served.
  db.scalar("WITH c AS (UPDATE survey_file_chunks SET data = 'XXXXXXX' WHERE seq = 1 RETURNING 1) SELECT count(*) FROM c");
  EXPECT_THROW(store.read_file(survey, "nav.csv"), std::runtime_error);
}

// Issue 37 fault 2: a scratch copy whose tail the disk refused at close (the file fits the
// stream's buffer) went unnoticed, and FinalizeSurvey judged the cut copy "not valid JSON".
TEST(SurveyStore, ACopyTheDiskRefusesIsAWriteError) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool);
  const std::int64_t survey =
      store.create_survey(store.create_tenant("acme"), "lake", {{"survey.json", bytes_of(R"({"name": "lake"})")}});
  try {
    store.export_file(survey, "survey.json", "/dev/full");  // refuses every write with ENOSPC
    ADD_FAILURE() << "the copy did not throw";
  } catch (const WriteError& error) {
    EXPECT_TRUE(error.out_of_space()) << error.what();
  }
}

TEST(SurveyStore, ASurveyInsertThatFailsHalfwayLeavesNothing) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool, 4);
  const std::int64_t tenant = store.create_tenant("acme");
  // The second file collides with the first inside the database, after the survey row, the
  // first file and its chunks are written.
  try {
    store.create_survey(tenant, "lake", {{"nav.csv", bytes_of("0123456789")}, {"nav.csv", bytes_of("again")}});
    FAIL() << "a survey with two files of one name";
  } catch (const DatabaseError& error) {
    EXPECT_EQ(error.sqlstate(), "23505");
  }
  EXPECT_EQ(rows_under_surveys(db), 0);
  // The pool's connection is clean, and the same name can be used now.
  EXPECT_GT(store.create_survey(tenant, "lake", {{"nav.csv", bytes_of("ok")}}), 0);
}

TEST(SurveyStore, BadNamesAreRefusedBeforeAnythingIsWritten) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool);
  const std::int64_t tenant = store.create_tenant("acme");
  for (const char* name : {"../etc/passwd", "", ".hidden", "a b", "dir/file"})
    EXPECT_THROW(store.create_survey(tenant, "lake", {{"ok.csv", {}}, {name, {}}}), std::invalid_argument) << name;
  EXPECT_THROW(store.create_survey(tenant, "", {}), std::invalid_argument);
  EXPECT_THROW(store.create_tenant(""), std::invalid_argument);
  try {
    store.create_survey(tenant + 99, "lake", {});
    FAIL() << "a survey for a tenant that does not exist";
  } catch (const DatabaseError& error) {
    EXPECT_EQ(error.sqlstate(), "23503");
  }
  EXPECT_EQ(rows_under_surveys(db), 0);
}

TEST(SurveyStore, ASurveyHoldsAtMostItsLimitOfFiles) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool);
  const std::int64_t survey = store.create_survey(store.create_tenant("acme"), "mission", {});
  const auto files = [&] { return db.scalar("SELECT count(*) FROM survey_files"); };
  db.scalar("WITH f AS (INSERT INTO survey_files (survey_id, name, size_bytes, sha256, chunk_count, committed_bytes, complete)"
            " SELECT " + std::to_string(survey) + ", 'line' || g || '.gsf', 0, sha256(''::bytea), 0, 0, true"
            " FROM generate_series(1, " + std::to_string(kMaxFilesPerSurvey - 1) + ") g RETURNING 1) SELECT count(*) FROM f");
  store.begin_upload(survey, "nav.csv", 3, sha256(bytes_of("abc")));  // the last one allowed
  try {
    store.begin_upload(survey, "pings.csv", 3, sha256(bytes_of("abc")));
    FAIL() << "a survey took more than " << kMaxFilesPerSurvey << " files";
  } catch (const UploadError& error) {
    EXPECT_EQ(error.kind(), UploadError::Kind::kTooMany);
    EXPECT_EQ(std::string(error.what()), "file_name: survey " + std::to_string(survey) + " holds 1000 files, the most a survey may hold");
  }
  // Declaring a file it holds again (resumed or replaced) adds none.
  store.begin_upload(survey, "nav.csv", 4, sha256(bytes_of("abcd")));
  EXPECT_EQ(files(), kMaxFilesPerSurvey);
}

// A tenant's quota counts what every survey's files declare; a declaration past it is refused and
// changes nothing; a resumed declaration is not counted twice; other tenants are not counted.
TEST(SurveyStore, ADeclarationPastTheTenantsQuotaIsRefused) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool);
  const std::int64_t acme = store.create_tenant("acme");
  const std::int64_t other = store.create_tenant("other");
  const std::int64_t first = store.create_survey(acme, "first", "", nlohmann::json::object(), nlohmann::json::object());
  const std::int64_t second = store.create_survey(acme, "second", "", nlohmann::json::object(), nlohmann::json::object());
  store.begin_upload(store.create_survey(other, "theirs", "", nlohmann::json::object(), nlohmann::json::object()), "pings.csv", 5000, sha256(bytes_of("x")));
  EXPECT_EQ(store.storage_use(acme).quota_bytes, std::nullopt);
  store.set_quota(acme, 1000);
  store.begin_upload(first, "nav.csv", 600, sha256(bytes_of("a")));
  store.begin_upload(first, "nav.csv", 600, sha256(bytes_of("a")));  // resumed: still 600
  const long long rows = rows_under_surveys(db);
  try {
    store.begin_upload(second, "pings.csv", 500, sha256(bytes_of("b")));
    FAIL() << "a declaration past the quota was taken";
  } catch (const UploadError& error) {
    EXPECT_EQ(error.kind(), UploadError::Kind::kQuota);
    EXPECT_STREQ(error.what(), "size_bytes: 500 more bytes would take this tenant's files to 1100 bytes, over its quota of "
                               "1000; delete surveys or ask the operator for more");
  }
  // A changed declaration of a file past the quota leaves the old one in place.
  EXPECT_THROW(store.begin_upload(first, "nav.csv", 1001, sha256(bytes_of("c"))), UploadError);
  EXPECT_EQ(rows_under_surveys(db), rows);
  EXPECT_EQ(store.upload_state(first, "nav.csv")->size_bytes, 600);
  store.begin_upload(second, "pings.csv", 400, sha256(bytes_of("b")));  // exactly the quota
  EXPECT_EQ(store.storage_use(acme).stored_bytes, 1000);
  EXPECT_EQ(store.storage_use(acme).quota_bytes, 1000);
  store.set_quota(acme, std::nullopt);
  store.begin_upload(second, "survey.json", 10'000, sha256(bytes_of("d")));
  EXPECT_EQ(store.storage_use(acme).stored_bytes, 11'000);
}

TEST(SurveyStore, TokensAreStoredHashedAndCanBeRevoked) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool);
  const std::int64_t acme = store.create_tenant("acme");
  const std::int64_t other = store.create_tenant("other");
  const std::string token = store.issue_token(acme, "ci");
  const std::string second = store.issue_token(other, "laptop");
  EXPECT_NE(token, second);
  EXPECT_EQ(token.size(), 4u + 64u);
  EXPECT_EQ(store.tenant_of_token(token), acme);
  EXPECT_EQ(store.tenant_of_token(second), other);
  EXPECT_EQ(store.tenant_of_token("bst_guess"), std::nullopt);
  Connection connection(db.conninfo());
  EXPECT_EQ(connection.exec("SELECT count(*) FROM api_tokens WHERE token_sha256 = sha256(convert_to($1, 'UTF8'))",
                            {token}).int64(0, 0), 1);
  EXPECT_EQ(connection.exec("SELECT count(*) FROM api_tokens WHERE position(convert_to($1, 'UTF8') IN token_sha256) > 0"
                            " OR description = $1", {token}).int64(0, 0), 0);
  EXPECT_TRUE(store.revoke_token(token));
  EXPECT_FALSE(store.revoke_token(token));
  EXPECT_EQ(store.tenant_of_token(token), std::nullopt);
  EXPECT_EQ(store.tenant_of_token(second), other);

  // Listed without the secrets; revoked by the id the list shows.
  std::vector<TokenInfo> listed = store.list_tokens();
  ASSERT_EQ(listed.size(), 2u);
  EXPECT_EQ(listed[0].tenant, "acme");
  EXPECT_EQ(listed[0].description, "ci");
  EXPECT_TRUE(listed[0].revoked_at);
  EXPECT_FALSE(listed[1].revoked_at);
  EXPECT_EQ(store.list_tokens("other").size(), 1u);
  EXPECT_TRUE(store.list_tokens("nobody").empty());
  EXPECT_TRUE(store.revoke_token(listed[1].id));
  EXPECT_FALSE(store.revoke_token(listed[1].id));
  EXPECT_EQ(store.tenant_of_token(second), std::nullopt);
}

TEST(SurveyStore, ATokenIssuedForAWhileIsRefusedOnceItExpires) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool);
  const std::int64_t acme = store.create_tenant("acme");
  const std::string day = store.issue_token(acme, "one day", 86400);
  const std::string forever = store.issue_token(acme, "no expiry");
  EXPECT_EQ(store.tenant_of_token(day), acme);
  const std::vector<TokenInfo> listed = store.list_tokens();
  ASSERT_EQ(listed.size(), 2u);
  ASSERT_TRUE(listed[0].expires_at);
  EXPECT_NEAR(*listed[0].expires_at - listed[0].created_at, 86400, 1);
  EXPECT_FALSE(listed[1].expires_at);
  // A day later, as far as the token is concerned.
  Connection connection(db.conninfo());
  connection.exec("UPDATE api_tokens SET expires_at = now() - interval '1 second' WHERE description = 'one day'");
  EXPECT_EQ(store.tenant_of_token(day), std::nullopt);
  EXPECT_EQ(store.tenant_of_token(forever), acme);
  EXPECT_THROW(store.issue_token(acme, "negative", -5), std::invalid_argument);
}

TEST(SurveyStore, TheLatestValidationIsKept) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool);
  const std::int64_t survey = store.create_survey(store.create_tenant("acme"), "lake", {});
  EXPECT_EQ(store.validation(survey), std::nullopt);
  nlohmann::json problem = {{"file", "nav.csv"}, {"line", 5}, {"field", "easting"}, {"message", "not a number"}};
  store.save_validation(survey, {false, nlohmann::json::array({problem}), nullptr});
  std::optional<Validation> first = store.validation(survey);
  ASSERT_TRUE(first);
  EXPECT_FALSE(first->valid);
  EXPECT_EQ(first->problems[0], problem);
  EXPECT_TRUE(first->summary.is_null());
  store.save_validation(survey, {true, nlohmann::json::array(), {{"pings", 1200}}});
  std::optional<Validation> second = store.validation(survey);
  ASSERT_TRUE(second);
  EXPECT_TRUE(second->valid);
  EXPECT_EQ(second->summary["pings"], 1200);
  EXPECT_THROW(store.save_validation(survey, {true, nlohmann::json::object(), nullptr}), std::invalid_argument);
}

// Two CreateSurvey calls with one name can both pass the service's look-up; the second insert's
// unique violation is the name being taken (ALREADY_EXISTS), not a failure of the database.
TEST(SurveyStore, ANameTakenMeanwhileIsSaidSo) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool);
  const std::int64_t tenant = store.create_tenant("acme");
  const nlohmann::json none = nlohmann::json::object();
  store.create_survey(tenant, "lake", "", none, none);
  try {
    store.create_survey(tenant, "lake", "", none, none);
    FAIL() << "a name was taken twice";
  } catch (const SurveyNameTaken& taken) {
    EXPECT_STREQ(taken.what(), "name: a survey named 'lake' exists already");
  }
  EXPECT_GT(store.create_survey(store.create_tenant("other"), "lake", "", none, none), 0);  // names are per tenant
}

// FinalizeSurvey reads the files, validates them, then saves: an upload landing in between must
// not make a survey ready with content that was never validated.
TEST(SurveyStore, AValidationOfFilesThatChangedMeanwhileIsNotSaved) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool);
  const std::int64_t survey = store.create_survey(store.create_tenant("acme"), "lake", "", nlohmann::json::object(), nlohmann::json::object());
  const Bytes nav = bytes_of("time,easting\n1,2\n");
  store.begin_upload(survey, "nav.csv", static_cast<std::int64_t>(nav.size()), sha256(nav));
  store.append_chunk(survey, "nav.csv", 0, Bytes(nav.begin(), nav.begin() + 4));
  const std::vector<UploadState> read = store.uploads(survey);  // what the validation saw
  store.append_chunk(survey, "nav.csv", 4, Bytes(nav.begin() + 4, nav.end()));  // the upload goes on
  const Validation ready{true, nlohmann::json::array(), {{"pings", 1}}};
  EXPECT_FALSE(store.save_validation_if_unchanged(survey, ready, read));
  EXPECT_EQ(store.validation(survey), std::nullopt);
  EXPECT_TRUE(store.save_validation_if_unchanged(survey, ready, store.uploads(survey)));
  EXPECT_TRUE(store.validation(survey)->valid);
  // Ready now: its files are fixed.
  EXPECT_THROW(store.begin_upload(survey, "pings.csv", 1, sha256(bytes_of("x"))), UploadError);
}

// An upload streamed from its start is hashed as it arrives (the file is not read back); the
// verdict must be the one the stored bytes would give, and a resumed upload still reads back.
TEST(SurveyStore, AStreamHashedAsItArrivesIsJudgedLikeTheStoredBytes) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool, 4);
  const std::int64_t survey = store.create_survey(store.create_tenant("acme"), "lake", "", nlohmann::json::object(), nlohmann::json::object());
  const Bytes nav = bytes_of("abcdefghij");
  const auto piece = [&](const Bytes& b, std::size_t from, std::size_t to) { return Bytes(b.begin() + from, b.begin() + to); };

  store.begin_upload(survey, "nav.csv", 10, sha256(nav));
  Sha256Stream whole;
  store.append_chunk(survey, "nav.csv", 0, piece(nav, 0, 4), &whole);
  store.append_chunk(survey, "nav.csv", 4, piece(nav, 4, 8), &whole);
  EXPECT_TRUE(store.append_chunk(survey, "nav.csv", 8, piece(nav, 8, 10), &whole).complete);
  EXPECT_EQ(store.read_file(survey, "nav.csv"), nav);

  // Other bytes than declared: refused and discarded, as when the file is read back.
  const Bytes other = bytes_of("abcdXfghij");
  store.begin_upload(survey, "pings.csv", 10, sha256(nav));
  Sha256Stream wrong;
  store.append_chunk(survey, "pings.csv", 0, piece(other, 0, 4), &wrong);
  store.append_chunk(survey, "pings.csv", 4, piece(other, 4, 8), &wrong);
  try {
    store.append_chunk(survey, "pings.csv", 8, piece(other, 8, 10), &wrong);
    FAIL() << "bytes that do not hash to the declared SHA-256 completed an upload";
  } catch (const UploadError& e) {
    EXPECT_EQ(e.kind(), UploadError::Kind::kChecksum);
  }
  EXPECT_EQ(store.upload_state(survey, "pings.csv")->committed_bytes, 0);

  // A stream cut after its first chunk; the next one starts mid-file and so reads back.
  Sha256Stream cut;
  store.append_chunk(survey, "pings.csv", 0, piece(nav, 0, 4), &cut);
  store.append_chunk(survey, "pings.csv", 4, piece(nav, 4, 8));
  EXPECT_TRUE(store.append_chunk(survey, "pings.csv", 8, piece(nav, 8, 10)).complete);
  EXPECT_EQ(store.read_file(survey, "pings.csv"), nav);
}

// An upload's chunks are stored a batch at a time: a refused chunk keeps the ones before it, as
// when each came in a transaction of its own, and bytes of every value come back as they went.
TEST(SurveyStore, ChunksStoredTogetherKeepThoseBeforeARefusedOne) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 1);
  SurveyStore store(pool, 4);
  const std::int64_t survey = store.create_survey(store.create_tenant("acme"), "lake", "", nlohmann::json::object(), nlohmann::json::object());
  Bytes file(40);  // ten chunks: read back in more than one round trip
  for (std::size_t i = 0; i < file.size(); ++i) file[i] = static_cast<std::uint8_t>(i % 2 == 0 ? 0 : 255 - i);
  const auto piece = [&](std::size_t from, std::size_t to) { return Bytes(file.begin() + from, file.begin() + to); };
  store.begin_upload(survey, "pings.csv", 40, sha256(file));

  // The third chunk skips a byte: the first two are kept, the refusal says where to resume.
  try {
    store.append_chunks(survey, "pings.csv", {{0, piece(0, 4)}, {4, piece(4, 8)}, {9, piece(9, 10)}});
    FAIL() << "a chunk past the committed bytes was stored";
  } catch (const UploadError& e) {
    EXPECT_EQ(e.kind(), UploadError::Kind::kBadOffset);
    EXPECT_NE(std::string(e.what()).find("8 bytes"), std::string::npos) << e.what();
  }
  EXPECT_EQ(store.upload_state(survey, "pings.csv")->committed_bytes, 8);

  // A batch refused at its first chunk (too large) changes nothing.
  EXPECT_THROW(store.append_chunks(survey, "pings.csv", {{8, piece(0, 5)}}), UploadError);
  EXPECT_EQ(store.upload_state(survey, "pings.csv")->committed_bytes, 8);

  std::vector<SurveyStore::Chunk> rest;
  for (std::size_t at = 8; at < file.size(); at += 4) rest.push_back({static_cast<std::int64_t>(at), piece(at, at + 4)});
  EXPECT_TRUE(store.append_chunks(survey, "pings.csv", rest).complete);
  EXPECT_EQ(store.read_file(survey, "pings.csv"), file);
  const std::filesystem::path copy = std::filesystem::temp_directory_path() / ("chunks-" + std::to_string(survey) + ".bin");
  store.export_file(survey, "pings.csv", copy);
  std::ifstream in(copy, std::ios::binary);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), std::string(file.begin(), file.end()));
  std::filesystem::remove(copy);
}

// A file streamed from the database reads as it was uploaded, and one whose storage no longer
// matches its upload is refused at its end rather than read as if whole.
TEST(SurveyStore, AFileReadStraightFromTheDatabaseIsCheckedAtItsEnd) {
  testing::FreshDatabase db;
  ConnectionPool pool(db.conninfo(), 2);
  SurveyStore store(pool, 5);
  const Bytes nav = bytes_of("time,easting,northing,depth,roll,pitch,heading\n1,2,3,4,5,6,7\n8,9,10,11,12,13,14\n");
  const std::int64_t survey = store.create_survey(store.create_tenant("acme"), "lake", {{"nav.csv", nav}});
  auto read_all_of = [&](std::size_t piece) {
    const std::unique_ptr<ByteSource> in = store.open_file(survey, "nav.csv");
    std::string text, buffer(piece, '\0');
    while (const std::size_t n = in->read(buffer.data(), buffer.size())) text.append(buffer.data(), n);
    return text;
  };
  EXPECT_EQ(read_all_of(3), std::string(nav.begin(), nav.end()));
  EXPECT_EQ(read_all_of(1000), std::string(nav.begin(), nav.end()));
  EXPECT_THROW(store.open_file(survey, "pings.csv"), std::out_of_range);

  // One chunk's five bytes overwritten in the database: the stream must not end as if whole.
  db.scalar("WITH c AS (UPDATE survey_file_chunks SET data = 'XXXXX' WHERE seq = 12 RETURNING 1) SELECT count(*) FROM c");
  EXPECT_THROW(read_all_of(1000), std::runtime_error);
}

}  // namespace
}  // namespace bathyslam::storage
