#include "server/storage/survey_store.h"

#include <openssl/evp.h>
#include <openssl/rand.h>

#include <algorithm>
#include <stdexcept>

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

Bytes token_hash(const std::string& token) { return digest_bytes(sha256(Bytes(token.begin(), token.end()))); }

}  // namespace

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
  return connection->exec("INSERT INTO tenants (name) VALUES ($1) RETURNING id", {name}).int64(0, 0);
}

std::string SurveyStore::issue_token(std::int64_t tenant_id, const std::string& description) {
  Sha256 secret{};
  if (RAND_bytes(secret.data(), static_cast<int>(secret.size())) != 1)
    throw std::runtime_error("no random bytes for a token");
  std::string token = "bst_" + hex(secret);
  auto connection = pool_.acquire();
  connection->exec("INSERT INTO api_tokens (tenant_id, token_sha256, description) VALUES ($1, $2, $3)",
                   {tenant_id, token_hash(token), description});
  return token;
}

std::optional<std::int64_t> SurveyStore::tenant_of_token(const std::string& token) {
  auto connection = pool_.acquire();
  Result row = connection->exec(
      "SELECT tenant_id FROM api_tokens WHERE token_sha256 = $1 AND revoked_at IS NULL", {token_hash(token)});
  if (row.rows() == 0) return std::nullopt;
  return row.int64(0, 0);
}

bool SurveyStore::revoke_token(const std::string& token) {
  auto connection = pool_.acquire();
  return connection
             ->exec("UPDATE api_tokens SET revoked_at = now() WHERE token_sha256 = $1 AND revoked_at IS NULL",
                    {token_hash(token)})
             .affected() == 1;
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
          .int64(0, 0);
  for (const FileUpload& file : files) {
    const std::size_t chunks = (file.content.size() + chunk_bytes_ - 1) / chunk_bytes_;
    std::int64_t file_id =
        connection
            ->exec("INSERT INTO survey_files (survey_id, name, size_bytes, sha256, chunk_count)"
                   " VALUES ($1, $2, $3, $4, $5) RETURNING id",
                   {survey_id, file.name, file.content.size(), digest_bytes(sha256(file.content)), chunks})
            .int64(0, 0);
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
    StoredFile file{rows.int64(row, 0), std::string(rows.text(row, 1)), rows.int64(row, 2), {},
                    static_cast<int>(rows.int64(row, 4))};
    Bytes digest = rows.bytes(row, 3);
    std::copy_n(digest.begin(), std::min(digest.size(), file.sha256.size()), file.sha256.begin());
    files.push_back(std::move(file));
  }
  return files;
}

Bytes SurveyStore::read_file(std::int64_t survey_id, const std::string& name) {
  auto connection = pool_.acquire();
  Result file = connection->exec(
      "SELECT id, size_bytes, sha256, chunk_count FROM survey_files WHERE survey_id = $1 AND name = $2",
      {survey_id, name});
  if (file.rows() == 0)
    throw std::out_of_range("survey " + std::to_string(survey_id) + " has no file '" + name + "'");
  Bytes content;
  content.reserve(static_cast<std::size_t>(file.int64(0, 1)));
  // One chunk per round trip keeps memory at one chunk beyond the result.
  for (std::int64_t seq = 0; seq < file.int64(0, 3); ++seq) {
    Result chunk = connection->exec("SELECT data FROM survey_file_chunks WHERE file_id = $1 AND seq = $2",
                                    {file.int64(0, 0), seq});
    if (chunk.rows() == 0) throw std::runtime_error("survey file '" + name + "': chunk " + std::to_string(seq) + " is missing");
    Bytes data = chunk.bytes(0, 0);
    content.insert(content.end(), data.begin(), data.end());
  }
  if (static_cast<std::int64_t>(content.size()) != file.int64(0, 1) || digest_bytes(sha256(content)) != file.bytes(0, 2))
    throw std::runtime_error("survey file '" + name + "' does not match the size and SHA-256 recorded at upload");
  return content;
}

void SurveyStore::save_validation(std::int64_t survey_id, const Validation& validation) {
  if (!validation.problems.is_array()) throw std::invalid_argument("validation problems must be a JSON array");
  auto connection = pool_.acquire();
  connection->exec(
      "INSERT INTO survey_validations (survey_id, valid, problems, summary) VALUES ($1, $2, $3, $4)"
      " ON CONFLICT (survey_id) DO UPDATE SET valid = EXCLUDED.valid, problems = EXCLUDED.problems,"
      " summary = EXCLUDED.summary, validated_at = now()",
      {survey_id, validation.valid, validation.problems.dump(),
       validation.summary.is_null() ? Param(std::nullopt) : Param(validation.summary.dump())});
}

std::optional<Validation> SurveyStore::validation(std::int64_t survey_id) {
  auto connection = pool_.acquire();
  Result row = connection->exec("SELECT valid, problems, summary FROM survey_validations WHERE survey_id = $1",
                                {survey_id});
  if (row.rows() == 0) return std::nullopt;
  Validation validation{row.boolean(0, 0), nlohmann::json::parse(row.text(0, 1)), nullptr};
  if (!row.is_null(0, 2)) validation.summary = nlohmann::json::parse(row.text(0, 2));
  return validation;
}

bool SurveyStore::delete_survey(std::int64_t survey_id) {
  auto connection = pool_.acquire();
  return connection->exec("DELETE FROM surveys WHERE id = $1", {survey_id}).affected() == 1;
}

}  // namespace bathyslam::storage
