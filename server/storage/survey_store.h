#pragma once
// Tenants, their API tokens, and their surveys: uploaded files (in chunks, with size and
// SHA-256) and the validation of each survey's bundle.
#include <openssl/evp.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/byte_source.h"
#include "server/storage/database.h"

namespace bathyslam::storage {

using Sha256 = std::array<std::uint8_t, 32>;
Sha256 sha256(const Bytes& bytes);
std::string hex(const Sha256& digest);

struct FileUpload {
  std::string name;  // a plain file name: letters, digits, '.', '_', '-'; no directories
  Bytes content;
};

struct StoredFile {
  std::int64_t id = 0;
  std::string name;
  std::int64_t size_bytes = 0;
  Sha256 sha256{};
  int chunk_count = 0;
};

// A survey as CreateSurvey declared it; ready once a validation found no error.
struct SurveyRecord {
  std::int64_t id = 0;
  std::int64_t tenant_id = 0;
  std::string name;
  std::string crs;
  nlohmann::json sonar = nlohmann::json::object();
  nlohmann::json vehicle = nlohmann::json::object();
  bool ready = false;
};

// One file's upload: declared size and SHA-256, and how much of it is stored.
struct UploadState {
  std::string name;
  std::int64_t size_bytes = 0;
  std::int64_t committed_bytes = 0;
  bool complete = false;
  Sha256 sha256{};

  bool operator==(const UploadState&) const = default;
};

// Why an upload step was refused; the service turns the kind into a status code.
// Files one survey may hold: the bundle's four, or a mission's GSF files (one a line, a few
// hundred at most), with room to spare; not millions of rows from one hostile client.
inline constexpr std::int64_t kMaxFilesPerSurvey = 1000;

class UploadError : public std::runtime_error {
 public:
  enum class Kind { kNotFound, kFinalized, kConflict, kBadOffset, kChecksum, kInvalid, kTooMany, kQuota };
  UploadError(Kind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

// CreateSurvey's name is the tenant's already: another call took it first (a unique violation,
// SQLSTATE 23505). A race between clients, not a database failure.
class SurveyNameTaken : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Validation {
  bool valid = false;
  nlohmann::json problems = nlohmann::json::array();
  nlohmann::json summary;  // null when the bundle did not parse
};

// What a tenant's uploaded files declare in all, and its quota (nullopt: none).
struct StorageUse {
  std::int64_t stored_bytes = 0;
  std::optional<std::int64_t> quota_bytes;
};

// An issued token as an operator lists it: never the token itself, which only its holder has.
struct TokenInfo {
  std::int64_t id = 0;
  std::string tenant;
  std::string description;
  double created_at = 0;  // seconds since the epoch
  std::optional<double> revoked_at;
  std::optional<double> expires_at;
};

// SHA-256 over data that arrives in pieces (an upload's chunks, a file read back chunk by chunk).
class Sha256Stream {
 public:
  Sha256Stream();
  void add(std::span<const std::uint8_t> bytes);
  Sha256 finish();  // once

 private:
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> context_;
};

class SurveyStore {
 public:
  // Files are split into chunks of `chunk_bytes` (1 MiB by default: well under PostgreSQL's
  // 1 GB field limit and small enough to stream).
  explicit SurveyStore(ConnectionPool& pool, std::size_t chunk_bytes = 1 << 20);

  std::int64_t create_tenant(const std::string& name);
  // A new random token for the tenant; only its hash is stored, so this is the one chance to
  // see it.
  // `valid_for_s` > 0: the token expires that many seconds from now; 0: it does not expire.
  std::string issue_token(std::int64_t tenant_id, const std::string& description, double valid_for_s = 0);
  std::optional<std::int64_t> tenant_of_token(const std::string& token);  // nullopt: unknown, revoked or expired
  bool revoke_token(const std::string& token);
  bool revoke_token(std::int64_t token_id);  // by the id that list_tokens shows
  // Every token, or a tenant's, oldest first.
  std::vector<TokenInfo> list_tokens(const std::optional<std::string>& tenant = std::nullopt);
  // The bytes a tenant's uploaded files may declare in all (nullopt: no quota). A declaration
  // that would pass it is refused (UploadError kQuota); what is stored already stays.
  void set_quota(std::int64_t tenant_id, std::optional<std::int64_t> quota_bytes);
  StorageUse storage_use(std::int64_t tenant_id);

  // The survey and all its files in one transaction: a failure anywhere leaves nothing.
  // Throws std::invalid_argument for a bad name before touching the database.
  std::int64_t create_survey(std::int64_t tenant_id, const std::string& name, const std::vector<FileUpload>& files);
  std::vector<StoredFile> files(std::int64_t survey_id);

  // An empty survey, its files to be uploaded one by one. Throws std::invalid_argument for an
  // empty name, SurveyNameTaken for a name the tenant already uses.
  std::int64_t create_survey(std::int64_t tenant_id, const std::string& name, const std::string& crs,
                             const nlohmann::json& sonar, const nlohmann::json& vehicle);
  std::optional<SurveyRecord> survey(std::int64_t survey_id);
  // A tenant's surveys by id, after `after_id`, at most `limit`; only `name` when given.
  std::vector<SurveyRecord> list_surveys(std::int64_t tenant_id, std::int64_t after_id, int limit,
                                         const std::optional<std::string>& name = std::nullopt);

  // Resumable uploads (UploadError on refusal). begin_upload declares a file; declaring it
  // again with the same size and SHA-256 keeps what is committed, with another it starts over.
  // A declaration that would take the tenant's files past its quota is refused (kQuota).
  UploadState begin_upload(std::int64_t survey_id, const std::string& name, std::int64_t size_bytes,
                           const Sha256& digest);
  // Stores `data` at `offset`, which must be the committed size. When the file is then whole,
  // verifies size and SHA-256; a mismatch discards the upload (kChecksum) so a retry starts clean.
  // `from_start`, for a stream of chunks that began at offset 0: the SHA-256 of the bytes before
  // `data`, which the chunk is added to, so that the whole file's digest is known without reading
  // the file back (a resumed upload reads back what an earlier stream committed).
  UploadState append_chunk(std::int64_t survey_id, const std::string& name, std::int64_t offset, const Bytes& data,
                           Sha256Stream* from_start = nullptr);
  // Several chunks that follow each other, in one transaction (a commit per chunk left the CPU
  // half idle, waiting on round trips): as append_chunk for each in turn. A chunk refused
  // (wrong offset, past the declared size, too large) throws after the chunks before it are
  // committed, as when each came alone.
  struct Chunk {
    std::int64_t offset = 0;
    Bytes data;
  };
  UploadState append_chunks(std::int64_t survey_id, const std::string& name, const std::vector<Chunk>& chunks,
                            Sha256Stream* from_start = nullptr);
  std::optional<UploadState> upload_state(std::int64_t survey_id, const std::string& name);
  std::vector<UploadState> uploads(std::int64_t survey_id);
  // Copies a complete file to `to` chunk by chunk, checking its SHA-256 on the way. A write the
  // disk refuses (full, failing) throws WriteError: never a shorter copy for a reader to judge.
  void export_file(std::int64_t survey_id, const std::string& name, const std::filesystem::path& to);
  // A complete file's bytes streamed from the database, holding a pool connection while it
  // lives; at the end its size and SHA-256 are checked against the upload's (std::runtime_error
  // naming the file when they differ). Throws std::out_of_range when there is no such file.
  std::unique_ptr<ByteSource> open_file(std::int64_t survey_id, const std::string& name);
  // Reassembles a file and checks its size and SHA-256; throws std::out_of_range if there is no
  // such file and std::runtime_error if it does not match what was uploaded.
  Bytes read_file(std::int64_t survey_id, const std::string& name);

  void save_validation(std::int64_t survey_id, const Validation& validation);
  // Saves `validation` only if the survey's uploads are still `validated` (what was read to make
  // it), checked and saved under a lock on the survey that every upload step takes too: a file
  // changed during validation cannot become part of a ready survey. False (nothing saved) if
  // they changed.
  bool save_validation_if_unchanged(std::int64_t survey_id, const Validation& validation,
                                    const std::vector<UploadState>& validated);
  std::optional<Validation> validation(std::int64_t survey_id);

  // Removes the survey and everything under it (files, jobs, results). False if there was none.
  bool delete_survey(std::int64_t survey_id);

 private:
  UploadError chunk_too_large(std::size_t bytes) const;

  ConnectionPool& pool_;
  std::size_t chunk_bytes_;
};

}  // namespace bathyslam::storage
