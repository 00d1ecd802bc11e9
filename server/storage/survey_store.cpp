#include "server/storage/survey_store.h"

#include <openssl/evp.h>
#include <openssl/rand.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <future>
#include <memory>
#include <stdexcept>
#include <type_traits>

#include "core/io/file_bytes.h"
#include "core/io/problem.h"

namespace bathyslam::storage {
namespace {

// The same rule as the schema's CHECK, checked first for a clear message.
bool plain_file_name(const std::string& name) {
  auto allowed = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
           c == '-';
  };
  return !name.empty() && name.front() != '.' && name.front() != '_' && name.front() != '-' &&
         std::all_of(name.begin(), name.end(), allowed);
}

Bytes digest_bytes(const Sha256& digest) { return Bytes(digest.begin(), digest.end()); }

Sha256 to_sha256(const Bytes& bytes) {
  Sha256 digest{};
  std::copy_n(bytes.begin(), std::min(bytes.size(), digest.size()), digest.begin());
  return digest;
}

// A file's chunks in order from the database, eight a query, the next eight fetched while the
// caller takes these (the database's reading and decompressing beside the caller's work;
// memory: sixteen chunks). With a `digest`, each query's chunks are added to it on the fetching
// thread, in order: a query starts only once the caller has taken the one before.
class ChunkStream {
 public:
  ChunkStream(Connection& connection, std::int64_t file_id, std::int64_t chunk_count, std::string name,
              Sha256Stream* digest = nullptr)
      : connection_(connection), file_id_(file_id), chunk_count_(chunk_count), name_(std::move(name)), digest_(digest) {
    fetch_from(0);
  }
  ChunkStream(const ChunkStream&) = delete;
  ChunkStream& operator=(const ChunkStream&) = delete;

  // The next chunk's bytes, valid until the next call; empty at the end (no chunk is empty).
  std::span<const std::uint8_t> next() {
    if (!rows_ || row_ == rows_->rows()) {
      if (!coming_.valid()) return {};
      const std::int64_t first = asked_;
      rows_.emplace(coming_.get());
      row_ = 0;
      const std::int64_t expected = std::min(chunk_count_, first + kChunksPerQuery) - first;
      if (rows_->rows() != expected)
        throw std::runtime_error("survey file '" + name_ + "': " + std::to_string(expected - rows_->rows()) + " of chunks " +
                                 std::to_string(first) + " to " + std::to_string(first + expected - 1) + " are missing");
      fetch_from(first + kChunksPerQuery);
    }
    // A binary result's cell is the value's bytes themselves.
    const std::string_view cell = rows_->text(row_++, 0);
    return {reinterpret_cast<const std::uint8_t*>(cell.data()), cell.size()};
  }

 private:
  static constexpr std::int64_t kChunksPerQuery = 8;

  void fetch_from(std::int64_t first) {
    if (first >= chunk_count_) return;
    asked_ = first;
    coming_ = std::async(std::launch::async, [this, first] {
      Result rows = connection_.exec_binary(
          "SELECT data FROM survey_file_chunks WHERE file_id = $1 AND seq >= $2 AND seq < $3 ORDER BY seq",
          {file_id_, first, std::min(chunk_count_, first + kChunksPerQuery)});
      if (digest_)
        for (int row = 0; row < rows.rows(); ++row) {
          const std::string_view cell = rows.text(row, 0);
          digest_->add({reinterpret_cast<const std::uint8_t*>(cell.data()), cell.size()});
        }
      return rows;
    });
  }

  Connection& connection_;
  std::int64_t file_id_, chunk_count_;
  std::string name_;
  Sha256Stream* digest_;
  std::optional<Result> rows_;
  int row_ = 0;
  std::int64_t asked_ = 0;       // the first chunk of the query coming
  std::future<Result> coming_;  // last: waited for before the rest goes
};

// The SHA-256 of a file's stored chunks, hashed as they are fetched.
Sha256 stored_sha256(Connection& connection, std::int64_t file_id, std::int64_t chunk_count, const std::string& name) {
  Sha256Stream digest;
  ChunkStream chunks(connection, file_id, chunk_count, name, &digest);
  while (!chunks.next().empty()) {
  }
  return digest.finish();
}

// A complete file read from the database as a ByteSource, its size and SHA-256 checked at the end
// (hashed beside the caller's parsing, by the chunks' fetching thread).
class StoredFileSource : public ByteSource {
 public:
  StoredFileSource(PooledConnection connection, std::int64_t file_id, std::int64_t chunk_count, std::int64_t size,
                   Sha256 sha256, std::string name)
      : connection_(std::move(connection)),
        size_(size),
        sha256_(sha256),
        name_(name),
        chunks_(std::make_unique<ChunkStream>(*connection_, file_id, chunk_count, std::move(name), &digest_)) {}

  std::size_t read(char* buffer, std::size_t size) override {
    std::size_t n = 0;
    while (n < size && !ended_) {
      if (left_.empty()) {
        left_ = chunks_->next();
        if (left_.empty()) {
          end();
          break;
        }
        read_ += static_cast<std::int64_t>(left_.size());
      }
      const std::size_t take = std::min(size - n, left_.size());
      std::memcpy(buffer + n, left_.data(), take);
      left_ = left_.subspan(take);
      n += take;
    }
    return n;
  }

 private:
  void end() {
    ended_ = true;
    if (read_ != size_ || digest_.finish() != sha256_)
      throw std::runtime_error("survey file '" + name_ + "' does not match the size and SHA-256 recorded at upload");
  }

  PooledConnection connection_;
  std::int64_t size_;
  Sha256 sha256_;
  std::string name_;
  Sha256Stream digest_;                  // before the chunks: they add to it until they go
  std::unique_ptr<ChunkStream> chunks_;  // after the connection: goes first
  std::span<const std::uint8_t> left_;
  std::int64_t read_ = 0;
  bool ended_ = false;
};

constexpr std::string_view kSurveyColumns =
    "SELECT s.id, s.tenant_id, s.name, s.crs, s.sonar, s.vehicle, coalesce(v.valid, false) AS ready"
    " FROM surveys s LEFT JOIN survey_validations v ON v.survey_id = s.id";

std::vector<SurveyRecord> survey_records(const Result& rows) {
  std::vector<SurveyRecord> surveys;
  for (int row = 0; row < rows.rows(); ++row) {
    SurveyRecord survey;
    survey.id = rows.int64(row, "id");
    survey.tenant_id = rows.int64(row, "tenant_id");
    survey.name = rows.text(row, "name");
    survey.crs = rows.text(row, "crs");
    survey.sonar = nlohmann::json::parse(rows.text(row, "sonar"));
    survey.vehicle = nlohmann::json::parse(rows.text(row, "vehicle"));
    survey.ready = rows.boolean(row, "ready");
    surveys.push_back(std::move(survey));
  }
  return surveys;
}

constexpr std::string_view kUploadColumns = "SELECT name, size_bytes, committed_bytes, complete, sha256 FROM survey_files";

UploadState upload_row(const Result& rows, int row) {
  UploadState state;
  state.name = rows.text(row, "name");
  state.size_bytes = rows.int64(row, "size_bytes");
  state.committed_bytes = rows.int64(row, "committed_bytes");
  state.complete = rows.boolean(row, "complete");
  state.sha256 = to_sha256(rows.bytes(row, "sha256"));
  return state;
}

// The survey's uploads in name order, on a connection the caller may hold in a transaction.
std::vector<UploadState> uploads_on(Connection& connection, std::int64_t survey_id) {
  Result rows = connection.exec(std::string(kUploadColumns) + " WHERE survey_id = $1 ORDER BY name", {survey_id});
  std::vector<UploadState> states;
  for (int row = 0; row < rows.rows(); ++row) states.push_back(upload_row(rows, row));
  return states;
}

Bytes token_hash(const std::string& token) { return digest_bytes(sha256(Bytes(token.begin(), token.end()))); }

}  // namespace

Sha256Stream::Sha256Stream() : context_(EVP_MD_CTX_new(), &EVP_MD_CTX_free) {
  if (!context_ || !EVP_DigestInit_ex(context_.get(), EVP_sha256(), nullptr)) throw std::runtime_error("SHA-256 failed");
}

void Sha256Stream::add(std::span<const std::uint8_t> bytes) {
  if (!EVP_DigestUpdate(context_.get(), bytes.data(), bytes.size())) throw std::runtime_error("SHA-256 failed");
}

Sha256 Sha256Stream::finish() {
  Sha256 digest{};
  unsigned int length = 0;
  if (!EVP_DigestFinal_ex(context_.get(), digest.data(), &length) || length != 32) throw std::runtime_error("SHA-256 failed");
  return digest;
}

Sha256 sha256(const Bytes& bytes) {
  Sha256 digest{};
  unsigned int length = 0;
  if (!EVP_Digest(bytes.data(), bytes.size(), digest.data(), &length, EVP_sha256(), nullptr) || length != 32)
    throw std::runtime_error("SHA-256 failed");
  return digest;
}

std::string hex(const Sha256& digest) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string text;
  for (std::uint8_t byte : digest) {
    text += kDigits[byte >> 4];
    text += kDigits[byte & 15];
  }
  return text;
}

SurveyStore::SurveyStore(ConnectionPool& pool, std::size_t chunk_bytes) : pool_(pool), chunk_bytes_(chunk_bytes) {
  if (chunk_bytes_ == 0) throw std::invalid_argument("survey store: chunk size must be positive");
}

std::int64_t SurveyStore::create_tenant(const std::string& name) {
  if (name.empty()) throw std::invalid_argument("a tenant needs a name");
  auto connection = pool_.acquire();
  return connection->exec("INSERT INTO tenants (name) VALUES ($1) RETURNING id", {name}).int64(0, "id");
}

std::string SurveyStore::issue_token(std::int64_t tenant_id, const std::string& description, double valid_for_s) {
  if (!(valid_for_s >= 0)) throw std::invalid_argument("a token's validity must be positive seconds, or 0 for none");
  Sha256 secret{};
  if (RAND_bytes(secret.data(), static_cast<int>(secret.size())) != 1)
    throw std::runtime_error("no random bytes for a token");
  std::string token = "bst_" + hex(secret);
  auto connection = pool_.acquire();
  std::optional<double> valid_for;
  if (valid_for_s > 0) valid_for = valid_for_s;
  connection->exec("INSERT INTO api_tokens (tenant_id, token_sha256, description, expires_at)"
                   " VALUES ($1, $2, $3, now() + make_interval(secs => $4))",
                   {tenant_id, token_hash(token), description, valid_for});
  return token;
}

std::optional<std::int64_t> SurveyStore::tenant_of_token(const std::string& token) {
  auto connection = pool_.acquire();
  Result row = connection->exec(
      "SELECT tenant_id FROM api_tokens WHERE token_sha256 = $1 AND revoked_at IS NULL"
      " AND (expires_at IS NULL OR expires_at > now())",
      {token_hash(token)});
  if (row.rows() == 0) return std::nullopt;
  return row.int64(0, "tenant_id");
}

bool SurveyStore::revoke_token(const std::string& token) {
  auto connection = pool_.acquire();
  return connection
             ->exec("UPDATE api_tokens SET revoked_at = now() WHERE token_sha256 = $1 AND revoked_at IS NULL",
                    {token_hash(token)})
             .affected() == 1;
}

bool SurveyStore::revoke_token(std::int64_t token_id) {
  auto connection = pool_.acquire();
  return connection->exec("UPDATE api_tokens SET revoked_at = now() WHERE id = $1 AND revoked_at IS NULL", {token_id})
             .affected() == 1;
}

std::vector<TokenInfo> SurveyStore::list_tokens(const std::optional<std::string>& tenant) {
  auto connection = pool_.acquire();
  Result rows = connection->exec(
      "SELECT t.id, n.name AS tenant, t.description, extract(epoch FROM t.created_at)::float8 AS created_at,"
      " extract(epoch FROM t.revoked_at)::float8 AS revoked_at, extract(epoch FROM t.expires_at)::float8 AS expires_at"
      " FROM api_tokens t JOIN tenants n ON n.id = t.tenant_id"
      " WHERE $1::text IS NULL OR n.name = $1 ORDER BY t.id",
      {tenant});
  std::vector<TokenInfo> tokens;
  for (int row = 0; row < rows.rows(); ++row) {
    TokenInfo token;
    token.id = rows.int64(row, "id");
    token.tenant = rows.text(row, "tenant");
    token.description = rows.text(row, "description");
    token.created_at = rows.float8(row, "created_at");
    if (!rows.is_null(row, "revoked_at")) token.revoked_at = rows.float8(row, "revoked_at");
    if (!rows.is_null(row, "expires_at")) token.expires_at = rows.float8(row, "expires_at");
    tokens.push_back(std::move(token));
  }
  return tokens;
}

std::int64_t SurveyStore::create_survey(std::int64_t tenant_id, const std::string& name,
                                        const std::vector<FileUpload>& files) {
  if (name.empty()) throw std::invalid_argument("a survey needs a name");
  for (const FileUpload& file : files)
    if (!plain_file_name(file.name))
      throw std::invalid_argument("survey file name '" + file.name +
                                  "': use letters, digits, '.', '_' and '-', starting with a letter or digit");
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  std::int64_t survey_id =
      connection->exec("INSERT INTO surveys (tenant_id, name) VALUES ($1, $2) RETURNING id", {tenant_id, name})
          .int64(0, "id");
  for (const FileUpload& file : files) {
    const std::size_t chunks = (file.content.size() + chunk_bytes_ - 1) / chunk_bytes_;
    std::int64_t file_id =
        connection
            ->exec("INSERT INTO survey_files (survey_id, name, size_bytes, sha256, chunk_count, committed_bytes, complete)"
                   " VALUES ($1, $2, $3, $4, $5, $3, true) RETURNING id",
                   {survey_id, file.name, file.content.size(), digest_bytes(sha256(file.content)), chunks})
            .int64(0, "id");
    for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
      auto begin = file.content.begin() + static_cast<std::ptrdiff_t>(chunk * chunk_bytes_);
      auto end = file.content.begin() + static_cast<std::ptrdiff_t>(std::min(file.content.size(), (chunk + 1) * chunk_bytes_));
      connection->exec("INSERT INTO survey_file_chunks (file_id, seq, data) VALUES ($1, $2, $3)",
                       {file_id, chunk, Bytes(begin, end)});
    }
  }
  transaction.commit();
  return survey_id;
}

std::vector<StoredFile> SurveyStore::files(std::int64_t survey_id) {
  auto connection = pool_.acquire();
  Result rows = connection->exec(
      "SELECT id, name, size_bytes, sha256, chunk_count FROM survey_files WHERE survey_id = $1 ORDER BY name",
      {survey_id});
  std::vector<StoredFile> files;
  for (int row = 0; row < rows.rows(); ++row) {
    StoredFile file;
    file.id = rows.int64(row, "id");
    file.name = rows.text(row, "name");
    file.size_bytes = rows.int64(row, "size_bytes");
    file.sha256 = to_sha256(rows.bytes(row, "sha256"));
    file.chunk_count = static_cast<int>(rows.int64(row, "chunk_count"));
    files.push_back(std::move(file));
  }
  return files;
}

Bytes SurveyStore::read_file(std::int64_t survey_id, const std::string& name) {
  const std::string content = read_all(*open_file(survey_id, name));
  return Bytes(content.begin(), content.end());
}

namespace {

void upsert_validation(Connection& connection, std::int64_t survey_id, const Validation& validation) {
  if (!validation.problems.is_array()) throw std::invalid_argument("validation problems must be a JSON array");
  connection.exec(
      "INSERT INTO survey_validations (survey_id, valid, problems, summary) VALUES ($1, $2, $3, $4)"
      " ON CONFLICT (survey_id) DO UPDATE SET valid = EXCLUDED.valid, problems = EXCLUDED.problems,"
      " summary = EXCLUDED.summary, validated_at = now()",
      {survey_id, validation.valid, validation.problems.dump(),
       validation.summary.is_null() ? Param(std::nullopt) : Param(validation.summary.dump())});
}

}  // namespace

void SurveyStore::save_validation(std::int64_t survey_id, const Validation& validation) {
  auto connection = pool_.acquire();
  upsert_validation(*connection, survey_id, validation);
}

bool SurveyStore::save_validation_if_unchanged(std::int64_t survey_id, const Validation& validation,
                                               const std::vector<UploadState>& validated) {
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  connection->exec("SELECT 1 FROM surveys WHERE id = $1 FOR UPDATE", {survey_id});
  if (uploads_on(*connection, survey_id) != validated) return false;
  upsert_validation(*connection, survey_id, validation);
  transaction.commit();
  return true;
}

std::optional<Validation> SurveyStore::validation(std::int64_t survey_id) {
  auto connection = pool_.acquire();
  Result row = connection->exec("SELECT valid, problems, summary FROM survey_validations WHERE survey_id = $1",
                                {survey_id});
  if (row.rows() == 0) return std::nullopt;
  Validation validation;
  validation.valid = row.boolean(0, "valid");
  validation.problems = nlohmann::json::parse(row.text(0, "problems"));
  if (!row.is_null(0, "summary")) validation.summary = nlohmann::json::parse(row.text(0, "summary"));
  return validation;
}

bool SurveyStore::delete_survey(std::int64_t survey_id) {
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  // Its jobs go with it, as those it is the first survey of do by the foreign key's cascade, and
  // so do the jobs of several surveys that joined it.
  connection->exec("DELETE FROM jobs WHERE id IN (SELECT job_id FROM job_surveys WHERE survey_id = $1)", {survey_id});
  const bool deleted = connection->exec("DELETE FROM surveys WHERE id = $1", {survey_id}).affected() == 1;
  transaction.commit();
  return deleted;
}

std::int64_t SurveyStore::create_survey(std::int64_t tenant_id, const std::string& name, const std::string& crs,
                                        const nlohmann::json& sonar, const nlohmann::json& vehicle) {
  if (name.empty()) throw std::invalid_argument("name: a survey needs a name");
  if (!sonar.is_object() || !vehicle.is_object()) throw std::invalid_argument("sonar and vehicle must be JSON objects");
  auto connection = pool_.acquire();
  try {
    return connection
        ->exec("INSERT INTO surveys (tenant_id, name, crs, sonar, vehicle) VALUES ($1, $2, $3, $4, $5) RETURNING id",
               {tenant_id, name, crs, sonar.dump(), vehicle.dump()})
        .int64(0, "id");
  } catch (const DatabaseError& error) {
    if (error.sqlstate() == "23505") throw SurveyNameTaken("name: a survey named " + quoted_input(name) + " exists already");
    throw;
  }
}

std::optional<SurveyRecord> SurveyStore::survey(std::int64_t survey_id) {
  auto connection = pool_.acquire();
  std::vector<SurveyRecord> found =
      survey_records(connection->exec(std::string(kSurveyColumns) + " WHERE s.id = $1", {survey_id}));
  if (found.empty()) return std::nullopt;
  return found.front();
}

std::vector<SurveyRecord> SurveyStore::list_surveys(std::int64_t tenant_id, std::int64_t after_id, int limit,
                                                    const std::optional<std::string>& name) {
  auto connection = pool_.acquire();
  return survey_records(connection->exec(std::string(kSurveyColumns) +
                                             " WHERE s.tenant_id = $1 AND s.id > $2 AND ($4::text IS NULL OR s.name = $4)"
                                             " ORDER BY s.id LIMIT $3",
                                         {tenant_id, after_id, limit, name}));
}

namespace {

// What the tenant's files declare in all, and its quota, on a connection the caller may hold in
// a transaction.
StorageUse storage_use_on(Connection& connection, std::int64_t tenant_id) {
  Result row = connection.exec(
      "SELECT t.quota_bytes, (SELECT coalesce(sum(f.size_bytes), 0) FROM survey_files f JOIN surveys s ON s.id = f.survey_id"
      " WHERE s.tenant_id = t.id)::bigint AS stored FROM tenants t WHERE t.id = $1",
      {tenant_id});
  if (row.rows() == 0) throw std::out_of_range("no tenant " + std::to_string(tenant_id));
  return {row.int64(0, "stored"), row.optional_int64(0, "quota_bytes")};
}

// Refuses a declaration of `size_bytes` more that would pass the tenant's quota. Under a lock on
// the tenant's row (NO KEY: a survey created meanwhile need not wait), so that concurrent
// declarations are counted one after the other. The caller holds the survey's lock first; a job's
// submit locks the tenant, then (its foreign key) the survey, but only of a finalized survey,
// which begin_upload refuses before it gets here: the two orders never meet on one survey.
void check_quota(Connection& connection, std::int64_t survey_id, std::int64_t size_bytes) {
  const std::int64_t tenant =
      connection
          .exec("SELECT t.id FROM tenants t JOIN surveys s ON s.tenant_id = t.id WHERE s.id = $1 FOR NO KEY UPDATE OF t",
                {survey_id})
          .int64(0, "id");
  const StorageUse use = storage_use_on(connection, tenant);
  if (use.quota_bytes && size_bytes > *use.quota_bytes - use.stored_bytes)  // no sum to overflow
    throw UploadError(UploadError::Kind::kQuota,
                      "size_bytes: " + std::to_string(size_bytes) + " more bytes would take this tenant's files to " +
                          std::to_string(static_cast<unsigned long long>(use.stored_bytes) + static_cast<unsigned long long>(size_bytes)) +
                          " bytes, over its quota of " +
                          std::to_string(*use.quota_bytes) + "; delete surveys or ask the operator for more");
}

}  // namespace

void SurveyStore::set_quota(std::int64_t tenant_id, std::optional<std::int64_t> quota_bytes) {
  auto connection = pool_.acquire();
  if (connection->exec("UPDATE tenants SET quota_bytes = $2 WHERE id = $1", {tenant_id, quota_bytes}).affected() != 1)
    throw std::out_of_range("no tenant " + std::to_string(tenant_id));
}

StorageUse SurveyStore::storage_use(std::int64_t tenant_id) {
  auto connection = pool_.acquire();
  return storage_use_on(*connection, tenant_id);
}

UploadState SurveyStore::begin_upload(std::int64_t survey_id, const std::string& name, std::int64_t size_bytes,
                                      const Sha256& digest) {
  if (!plain_file_name(name))
    throw UploadError(UploadError::Kind::kInvalid, "file_name: '" + name +
                                                       "': use letters, digits, '.', '_' and '-', starting with a letter or digit");
  if (size_bytes < 0) throw UploadError(UploadError::Kind::kInvalid, "size_bytes: must not be negative");
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  // Locks the survey row: two uploads of the same file cannot both create it.
  Result survey = connection->exec(
      "SELECT coalesce(v.valid, false) AS valid FROM surveys s LEFT JOIN survey_validations v ON v.survey_id = s.id"
      " WHERE s.id = $1 FOR UPDATE OF s",
      {survey_id});
  if (survey.rows() == 0) throw UploadError(UploadError::Kind::kNotFound, "no survey " + std::to_string(survey_id));
  if (survey.boolean(0, "valid"))
    throw UploadError(UploadError::Kind::kFinalized, "survey " + std::to_string(survey_id) + " is finalized: its files are fixed");
  Result existing = connection->exec(std::string(kUploadColumns) + " WHERE survey_id = $1 AND name = $2", {survey_id, name});
  if (existing.rows() == 1) {
    UploadState state = upload_row(existing, 0);
    if (state.size_bytes == size_bytes && state.sha256 == digest) return state;  // a resumed upload
    connection->exec("DELETE FROM survey_files WHERE survey_id = $1 AND name = $2", {survey_id, name});
  } else if (const std::int64_t files =
                 connection->exec("SELECT count(*) AS files FROM survey_files WHERE survey_id = $1", {survey_id})
                     .int64(0, "files");
             files >= kMaxFilesPerSurvey) {
    // Counted under the survey's lock: concurrent uploads cannot pass the limit together.
    throw UploadError(UploadError::Kind::kTooMany, "file_name: survey " + std::to_string(survey_id) + " holds " +
                                                       std::to_string(files) + " files, the most a survey may hold");
  }
  check_quota(*connection, survey_id, size_bytes);  // a changed declaration's old row is gone by now
  Result created = connection->exec(
      "INSERT INTO survey_files (survey_id, name, size_bytes, sha256, chunk_count, committed_bytes, complete)"
      " VALUES ($1, $2, $3, $4, 0, 0, false) RETURNING name, size_bytes, committed_bytes, complete, sha256",
      {survey_id, name, size_bytes, digest_bytes(digest)});
  UploadState state = upload_row(created, 0);
  transaction.commit();
  if (size_bytes == 0) return append_chunk(survey_id, name, 0, {});  // nothing to wait for: verify now
  return state;
}

namespace {

// A file being uploaded, as append_chunk finds it (locked).
struct UploadRow {
  std::int64_t file_id = 0, size = 0, committed = 0, chunks = 0;
  bool complete = false, survey_finalized = false;
  Bytes sha256;
};

UploadRow upload_row_of(const Result& r) {
  UploadRow row;
  row.file_id = r.int64(0, "id");
  row.size = r.int64(0, "size_bytes");
  row.committed = r.int64(0, "committed_bytes");
  row.chunks = r.int64(0, "chunk_count");
  row.complete = r.boolean(0, "complete");
  row.survey_finalized = r.boolean(0, "finalized");
  row.sha256 = r.bytes(0, "sha256");
  return row;
}

// The upload rules: a chunk continues a file that is neither complete nor in a finalized survey,
// exactly where its committed bytes end, and does not run past its declared size.
void check_chunk(const UploadRow& file, std::int64_t survey_id, const std::string& name, std::int64_t offset,
                 std::size_t bytes) {
  if (file.survey_finalized) throw UploadError(UploadError::Kind::kFinalized, "survey " + std::to_string(survey_id) + " is finalized");
  if (file.complete) throw UploadError(UploadError::Kind::kConflict, "'" + name + "' is complete already");
  if (offset != file.committed)
    throw UploadError(UploadError::Kind::kBadOffset, "offset: " + std::to_string(offset) + " but " +
                                                         std::to_string(file.committed) + " bytes of '" + name +
                                                         "' are committed; resume there");
  const std::int64_t end = file.committed + static_cast<std::int64_t>(bytes);
  if (end > file.size)
    throw UploadError(UploadError::Kind::kInvalid, "data: '" + name + "' was declared " + std::to_string(file.size) +
                                                       " bytes; this chunk would end at " + std::to_string(end));
}

// Rows of survey_file_chunks in COPY's binary format: a header, then per row its field count
// and each field's length and big-endian bytes, then -1. One COPY stores a batch of chunks at
// about the rate of PostgreSQL's own bulk load (bench/ingest.sh), an INSERT each at two thirds.
class ChunkRows {
 public:
  ChunkRows() { bytes_.append("PGCOPY\n\377\r\n\0\0\0\0\0\0\0\0\0", 19); }
  void add(std::int64_t file_id, std::int64_t seq, const Bytes& data) {
    put<std::int16_t>(3);
    put<std::int32_t>(8);
    put<std::int64_t>(file_id);
    put<std::int32_t>(4);
    put<std::int32_t>(static_cast<std::int32_t>(seq));
    put<std::int32_t>(static_cast<std::int32_t>(data.size()));
    bytes_.append(reinterpret_cast<const char*>(data.data()), data.size());
    ++rows_;
  }
  bool empty() const { return rows_ == 0; }
  std::string_view bytes() {
    if (!ended_) put<std::int16_t>(-1);
    ended_ = true;
    return bytes_;
  }

 private:
  template <typename T>
  void put(T value) {
    using U = std::make_unsigned_t<T>;
    const U bits = static_cast<U>(value);
    for (int shift = 8 * (static_cast<int>(sizeof(T)) - 1); shift >= 0; shift -= 8) bytes_.push_back(static_cast<char>(bits >> shift));
  }

  std::string bytes_;
  std::size_t rows_ = 0;
  bool ended_ = false;
};

}  // namespace

UploadState SurveyStore::append_chunk(std::int64_t survey_id, const std::string& name, std::int64_t offset,
                                      const Bytes& data, Sha256Stream* from_start) {
  if (data.size() > chunk_bytes_) throw chunk_too_large(data.size());  // before touching the database
  return append_chunks(survey_id, name, {{offset, data}}, from_start);
}

UploadError SurveyStore::chunk_too_large(std::size_t bytes) const {
  return UploadError(UploadError::Kind::kInvalid,
                     "data: a chunk holds at most " + std::to_string(chunk_bytes_) + " bytes, got " + std::to_string(bytes));
}

UploadState SurveyStore::append_chunks(std::int64_t survey_id, const std::string& name, const std::vector<Chunk>& chunks,
                                       Sha256Stream* from_start) {
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  // Waits for a finalize in progress (which locks the survey FOR UPDATE) and makes it wait for
  // these chunks; the statement below then sees whether the survey became ready meanwhile.
  connection->exec("SELECT 1 FROM surveys WHERE id = $1 FOR SHARE", {survey_id});
  const Result found = connection->exec(
      "SELECT f.id, f.size_bytes, f.committed_bytes, f.complete, f.sha256, f.chunk_count,"
      " coalesce(v.valid, false) AS finalized"
      " FROM survey_files f LEFT JOIN survey_validations v ON v.survey_id = f.survey_id"
      " WHERE f.survey_id = $1 AND f.name = $2 FOR UPDATE OF f",
      {survey_id, name});
  if (found.rows() == 0)
    throw UploadError(UploadError::Kind::kNotFound, "survey " + std::to_string(survey_id) + " has no upload of '" + name + "'");
  const UploadRow file = upload_row_of(found);
  UploadRow now = file;  // as each chunk finds the file
  ChunkRows rows;
  std::size_t accepted = 0;
  std::optional<UploadError> refused;
  for (const Chunk& chunk : chunks) {
    try {
      if (chunk.data.size() > chunk_bytes_) throw chunk_too_large(chunk.data.size());
      check_chunk(now, survey_id, name, chunk.offset, chunk.data.size());
    } catch (const UploadError& error) {
      refused = error;
      break;
    }
    if (from_start) from_start->add(chunk.data);
    if (!chunk.data.empty()) rows.add(file.file_id, now.chunks++, chunk.data);
    now.committed += static_cast<std::int64_t>(chunk.data.size());
    now.complete = now.committed == file.size;
    ++accepted;
  }
  if (accepted == 0 && refused) throw *refused;  // nothing changed: the transaction rolls back
  if (!rows.empty()) connection->copy_in("COPY survey_file_chunks (file_id, seq, data) FROM STDIN (FORMAT binary)", rows.bytes());
  if (now.complete) {
    const Sha256 received =
        from_start ? from_start->finish() : stored_sha256(*connection, file.file_id, now.chunks, name);
    if (received != to_sha256(file.sha256)) {
      // Discarded and committed before throwing, so that a retry starts from zero.
      connection->exec("DELETE FROM survey_file_chunks WHERE file_id = $1", {file.file_id});
      connection->exec("UPDATE survey_files SET committed_bytes = 0, chunk_count = 0 WHERE id = $1", {file.file_id});
      transaction.commit();
      throw UploadError(UploadError::Kind::kChecksum,
                        "sha256: the " + std::to_string(file.size) + " bytes received of '" + name + "' hash to " +
                            hex(received) + ", not the declared " + hex(to_sha256(file.sha256)) + "; the upload was discarded");
    }
  }
  Result updated = connection->exec(
      "UPDATE survey_files SET committed_bytes = $2, chunk_count = $3, complete = $4 WHERE id = $1"
      " RETURNING name, size_bytes, committed_bytes, complete, sha256",
      {file.file_id, now.committed, now.chunks, now.complete});
  transaction.commit();
  if (refused) throw *refused;  // after the chunks before it are kept
  return upload_row(updated, 0);
}

std::optional<UploadState> SurveyStore::upload_state(std::int64_t survey_id, const std::string& name) {
  auto connection = pool_.acquire();
  Result row = connection->exec(std::string(kUploadColumns) + " WHERE survey_id = $1 AND name = $2", {survey_id, name});
  if (row.rows() == 0) return std::nullopt;
  return upload_row(row, 0);
}

std::vector<UploadState> SurveyStore::uploads(std::int64_t survey_id) {
  auto connection = pool_.acquire();
  return uploads_on(*connection, survey_id);
}

void SurveyStore::export_file(std::int64_t survey_id, const std::string& name, const std::filesystem::path& to) {
  const std::unique_ptr<ByteSource> in = open_file(survey_id, name);
  std::ofstream out(to, std::ios::binary);
  std::vector<char> buffer(1 << 20);
  while (const std::size_t n = in->read(buffer.data(), buffer.size())) {
    out.write(buffer.data(), static_cast<std::streamsize>(n));
    if (!out) close_checked(out, to);  // at once, while errno still says why
  }
  close_checked(out, to);
}

std::unique_ptr<ByteSource> SurveyStore::open_file(std::int64_t survey_id, const std::string& name) {
  auto connection = pool_.acquire();
  Result file = connection->exec(
      "SELECT id, size_bytes, sha256, chunk_count FROM survey_files WHERE survey_id = $1 AND name = $2 AND complete",
      {survey_id, name});
  if (file.rows() == 0) throw std::out_of_range("survey " + std::to_string(survey_id) + " has no complete file '" + name + "'");
  return std::make_unique<StoredFileSource>(std::move(connection), file.int64(0, "id"), file.int64(0, "chunk_count"),
                                            file.int64(0, "size_bytes"), to_sha256(file.bytes(0, "sha256")), name);
}

}  // namespace bathyslam::storage
