// bathyslam upload BUNDLE: creates the survey (or finds the one of the same name that an
// interrupted upload left), uploads each file from where the server's committed size says,
// and finalizes it.
#include <openssl/evp.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include <nlohmann/json.hpp>

#include "bathyslam/v1/survey.grpc.pb.h"
#include "client/commands.h"
#include "client/remote.h"
#include "core/io/bundle.h"
#include "core/io/bundle_files.h"

namespace bathyslam::cli {
namespace {

constexpr std::size_t kChunkBytes = 1 << 20;  // the API's largest chunk

struct UploadOptions {
  Remote remote;
  std::string bundle;
  std::string name;
  std::int64_t stop_after_bytes = 0;  // > 0: stop there, as a cut connection would (to test resuming)
};

std::string file_sha256(const BundleFiles& files, std::string_view file) {
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> context(EVP_MD_CTX_new(), &EVP_MD_CTX_free);
  EVP_DigestInit_ex(context.get(), EVP_sha256(), nullptr);
  const std::unique_ptr<ByteSource> in = files.open(file);
  std::vector<char> buffer(4 << 20);
  while (const std::size_t n = in->read(buffer.data(), buffer.size())) EVP_DigestUpdate(context.get(), buffer.data(), n);
  std::array<unsigned char, 32> digest{};
  unsigned int length = 0;
  EVP_DigestFinal_ex(context.get(), digest.data(), &length);
  return std::string(digest.begin(), digest.end());
}

// The survey's name when survey.json has none: the folder's, or the tar's without ".tar".
std::string default_name(const std::filesystem::path& bundle) {
  return std::filesystem::is_directory(bundle) ? bundle.filename().string() : bundle.stem().string();
}

std::int64_t find_or_create_survey(v1::SurveyService::Stub& surveys, const UploadOptions& o, const BundleFiles& files,
                                   bool& ready) {
  if (!files.contains(kSurveyJsonFile)) throw std::runtime_error(o.bundle + ": no survey.json");
  nlohmann::json meta;
  try {
    meta = parse_bounded_json(read_at_most(*files.open(kSurveyJsonFile), kSurveyJsonLimits.max_bytes), kSurveyJsonLimits);
  } catch (const std::exception&) {
  }
  if (!meta.is_object())
    throw std::runtime_error(o.bundle + "/survey.json: not a JSON object (bathyslam inspect tells more)");
  const std::string name = !o.name.empty() ? o.name : meta.value("name", default_name(o.bundle));
  v1::ListSurveysRequest list;
  list.set_name(name);
  v1::ListSurveysResponse found;
  check("ListSurveys", surveys.ListSurveys(o.remote.context(30).get(), list, &found));
  if (found.surveys_size() > 0) {
    ready = found.surveys(0).state() == v1::Survey::READY;
    std::fprintf(stderr, "survey %lld '%s' exists%s\n", static_cast<long long>(found.surveys(0).id()), name.c_str(),
                 ready ? " and is ready" : ": resuming its upload");
    return found.surveys(0).id();
  }
  v1::CreateSurveyRequest create;
  create.set_name(name);
  create.set_crs(meta.value("crs", ""));
  create.set_sonar_json(meta.value("sonar", nlohmann::json::object()).dump());
  create.set_vehicle_json(meta.value("vehicle", nlohmann::json::object()).dump());
  v1::Survey survey;
  check("CreateSurvey", surveys.CreateSurvey(o.remote.context(30).get(), create, &survey));
  ready = false;
  return survey.id();
}

// Uploads one file from the committed size on; false when stopped by --stop-after-bytes.
bool upload_file(v1::SurveyService::Stub& surveys, const UploadOptions& o, std::int64_t survey_id,
                 const BundleFiles& files, std::string_view file, std::int64_t& budget) {
  const std::string name(file);
  const auto size = static_cast<std::int64_t>(files.size(file));
  const std::string digest = file_sha256(files, file);

  v1::GetUploadStatusRequest ask;
  ask.set_survey_id(survey_id);
  ask.set_file_name(name);
  v1::UploadStatus status;
  std::int64_t offset = 0;
  const grpc::Status asked = surveys.GetUploadStatus(o.remote.context(30).get(), ask, &status);
  if (asked.ok() && status.size_bytes() == size && status.sha256() == digest) {
    if (status.complete()) {
      std::fprintf(stderr, "  %-18s uploaded already (%s)\n", name.c_str(), megabytes(size).c_str());
      return true;
    }
    offset = status.committed_bytes();
    if (offset > 0) std::fprintf(stderr, "  resuming %s at %lld of %lld bytes\n", name.c_str(),
                                 static_cast<long long>(offset), static_cast<long long>(size));
  } else if (!asked.ok() && asked.error_code() != grpc::StatusCode::NOT_FOUND) {
    check("GetUploadStatus", asked);
  }

  auto context = o.remote.context();
  v1::UploadStatus reply;
  auto writer = surveys.UploadFile(context.get(), &reply);
  const std::unique_ptr<ByteSource> in = files.open(file, static_cast<std::uint64_t>(offset));
  v1::UploadFileRequest message;
  message.set_survey_id(survey_id);
  message.set_file_name(name);
  message.set_size_bytes(size);
  message.set_sha256(digest);
  const auto start = std::chrono::steady_clock::now();
  const std::int64_t first = offset;
  std::string buffer(kChunkBytes, '\0');
  bool first_message = true;
  while (first_message || offset < size) {
    std::size_t want = static_cast<std::size_t>(std::min<std::int64_t>(kChunkBytes, size - offset));
    if (o.stop_after_bytes > 0) want = static_cast<std::size_t>(std::min<std::int64_t>(want, budget));
    if (!first_message && want == 0) break;  // --stop-after-bytes used up
    if (read_fully(*in, buffer.data(), want) != want) throw std::runtime_error(name + ": shorter than " + std::to_string(size) + " bytes");
    message.set_offset(offset);
    message.set_data(buffer.data(), want);
    if (!writer->Write(message)) break;  // the server ended the call; Finish says why
    offset += static_cast<std::int64_t>(want);
    budget -= static_cast<std::int64_t>(want);
    first_message = false;
    message.clear_survey_id();
    message.clear_file_name();
    message.clear_size_bytes();
    message.clear_sha256();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    progress_line(name, size ? static_cast<double>(offset) / size : 1,
                  megabytes(offset) + " of " + megabytes(size) + ", " + megabytes((offset - first) / std::max(seconds, 1e-3)) + "/s");
  }
  writer->WritesDone();
  const grpc::Status done = writer->Finish();
  std::fprintf(stderr, "\n");
  check("UploadFile " + name, done);
  if (!reply.complete()) {
    std::fprintf(stderr, "  %s: stopped at %lld of %lld bytes; run the same command again to resume\n", name.c_str(),
                 static_cast<long long>(reply.committed_bytes()), static_cast<long long>(size));
    return false;
  }
  return true;
}

void run_upload(const UploadOptions& o) {
  auto channel = o.remote.channel();
  auto surveys = v1::SurveyService::NewStub(channel);
  const BundleFiles files(o.bundle);
  bool ready = false;
  const std::int64_t id = find_or_create_survey(*surveys, o, files, ready);
  if (!ready) {
    std::int64_t budget = o.stop_after_bytes;
    for (std::string_view file : {kSurveyJsonFile, kNavFile, kPingsFile, kReferenceNavFile}) {
      if (!files.contains(file)) continue;
      if (!upload_file(*surveys, o, id, files, file, budget)) throw std::runtime_error("upload interrupted (--stop-after-bytes)");
    }
    v1::FinalizeSurveyRequest finalize;
    finalize.set_survey_id(id);
    v1::Survey survey;
    check("FinalizeSurvey", surveys->FinalizeSurvey(o.remote.context(600).get(), finalize, &survey));
  }
  std::printf("survey %lld ready\n", static_cast<long long>(id));
}

}  // namespace

void add_upload_command(CLI::App& app) {
  auto o = std::make_shared<UploadOptions>();
  CLI::App* cmd = app.add_subcommand("upload", "Upload a survey bundle (resumes an interrupted upload) and finalize it");
  cmd->add_option("bundle", o->bundle, "survey bundle: a folder or a .tar of one")->required()->check(CLI::ExistingPath);
  cmd->add_option("--name", o->name, "survey name (default: survey.json's name)");
  cmd->add_option("--stop-after-bytes", o->stop_after_bytes, "stop after sending this many bytes, as a cut connection would");
  add_remote_options(cmd, o->remote);
  cmd->callback([o] { run_upload(*o); });
}

}  // namespace bathyslam::cli
