// bathyslam upload BUNDLE | A.gsf [B.gsf ...]: creates the survey (or finds the one of the same
// name that an interrupted upload left), uploads each file from where the server's committed
// size says, and finalizes it.
#include <openssl/evp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "bathyslam/v1/survey.grpc.pb.h"
#include "client/commands.h"
#include "client/remote.h"
#include "core/io/bundle.h"
#include "core/io/bundle_files.h"
#include "core/io/file_extension.h"
#include "core/io/survey_input.h"

namespace bathyslam::cli {
namespace {

constexpr std::size_t kChunkBytes = 1 << 20;  // the API's largest chunk

struct UploadOptions {
  Remote remote;
  std::vector<std::string> inputs;  // one bundle, or GSF files
  std::string crs;                  // GSF: the survey's CRS (default: the data's UTM zone)
  std::string reference_nav;        // GSF: uploaded as reference_nav.csv
  std::string name;
  std::int64_t stop_after_bytes = 0;  // > 0: stop there, as a cut connection would (to test resuming)
  double retry_seconds = 300;         // how long UNAVAILABLE answers are waited out
};

// One file to upload: the name the server stores it under, its size and its bytes from an offset.
struct LocalFile {
  std::string name;
  std::int64_t size = 0;
  std::function<std::unique_ptr<ByteSource>(std::uint64_t offset)> open;
};

// What the survey is declared as: its name, CRS, sonar and vehicle.
struct Declaration {
  std::string name, crs;
  nlohmann::json sonar = nlohmann::json::object(), vehicle = nlohmann::json::object();
};

std::string file_sha256(const LocalFile& file) {
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> context(EVP_MD_CTX_new(), &EVP_MD_CTX_free);
  EVP_DigestInit_ex(context.get(), EVP_sha256(), nullptr);
  const std::unique_ptr<ByteSource> in = file.open(0);
  std::vector<char> buffer(4 << 20);
  while (const std::size_t n = in->read(buffer.data(), buffer.size())) EVP_DigestUpdate(context.get(), buffer.data(), n);
  std::array<unsigned char, 32> digest{};
  unsigned int length = 0;
  EVP_DigestFinal_ex(context.get(), digest.data(), &length);
  return std::string(digest.begin(), digest.end());
}

// The bytes sent of every file, on one line (files go side by side), with lines said above it.
class Progress {
 public:
  explicit Progress(std::int64_t total) : total_(total) {}
  // `file` has `bytes` on the server (a resumed or retried file starts again where it stood).
  void at(const std::string& file, std::int64_t bytes) {
    std::lock_guard lock(mutex_);
    done_ += bytes - std::exchange(at_[file], bytes);
    const auto now = std::chrono::steady_clock::now();
    if (now - drawn_ < std::chrono::milliseconds(100) && done_ < total_) return;
    drawn_ = now;
    draw();
  }
  void say(const std::string& line) {
    std::lock_guard lock(mutex_);
    std::fprintf(stderr, "\r%-100s\r  %s\n", "", line.c_str());
    draw();
  }
  void end() {
    std::lock_guard lock(mutex_);
    draw();
    std::fprintf(stderr, "\n");
  }

 private:
  void draw() {
    const double seconds = std::max(1e-3, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
    progress_line("upload", total_ ? static_cast<double>(done_) / total_ : 1,
                  megabytes(done_) + " of " + megabytes(total_) + ", " + megabytes(done_ / seconds) + "/s");
  }

  std::mutex mutex_;
  std::int64_t total_, done_ = 0;
  std::map<std::string, std::int64_t> at_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point drawn_{};
};

// The survey's name when survey.json has none: the folder's, or the tar's without ".tar".
std::string default_name(const std::filesystem::path& bundle) {
  return std::filesystem::is_directory(bundle) ? bundle.filename().string() : bundle.stem().string();
}

// A bundle: survey.json declares it; its files in the bundle's order.
std::vector<LocalFile> bundle_files(const UploadOptions& o, Declaration& declared) {
  const auto files = std::make_shared<BundleFiles>(o.inputs.front());
  if (!files->contains(kSurveyJsonFile)) throw std::runtime_error(o.inputs.front() + ": no survey.json");
  nlohmann::json meta;
  try {
    meta = parse_bounded_json(read_at_most(*files->open(kSurveyJsonFile), kSurveyJsonLimits.max_bytes), kSurveyJsonLimits);
  } catch (const std::exception&) {
  }
  if (!meta.is_object())
    throw std::runtime_error(o.inputs.front() + "/survey.json: not a JSON object (bathyslam inspect tells more)");
  declared = {!o.name.empty() ? o.name : meta.value("name", default_name(o.inputs.front())), meta.value("crs", ""),
              meta.value("sonar", nlohmann::json::object()), meta.value("vehicle", nlohmann::json::object())};
  std::vector<LocalFile> out;
  for (std::string_view file : {kSurveyJsonFile, kNavFile, kPingsFile, kReferenceNavFile}) {
    if (!files->contains(file)) continue;
    out.push_back({std::string(file), static_cast<std::int64_t>(files->size(file)),
                   [files, file](std::uint64_t offset) { return files->open(file, offset); }});
  }
  return out;
}

// Sonar files (GSF or EM .all): declared by the options; each under its own file name, the
// reference navigation as reference_nav.csv. The server orders the files by time.
std::vector<LocalFile> sonar_files(const UploadOptions& o, Declaration& declared) {
  declared = {!o.name.empty() ? o.name : std::filesystem::path(o.inputs.front()).stem().string(), o.crs,
              nlohmann::json::object(), nlohmann::json::object()};
  auto local = [](const std::filesystem::path& path, std::string name) {
    return LocalFile{std::move(name), static_cast<std::int64_t>(std::filesystem::file_size(path)),
                     [path](std::uint64_t offset) { return std::make_unique<FileSource>(path, offset); }};
  };
  std::vector<LocalFile> out;
  for (const std::string& input : o.inputs) {
    const std::string name = std::filesystem::path(input).filename().string();
    if (!is_sonar_file_name(name))
      throw std::runtime_error(input + ": a sonar file name must be letters, digits, '.', '_' or '-' and end in .gsf, .all or .xtf");
    out.push_back(local(input, name));
  }
  if (!o.reference_nav.empty()) out.push_back(local(o.reference_nav, std::string(kReferenceNavFile)));
  return out;
}

std::int64_t find_or_create_survey(v1::SurveyService::Stub& surveys, const UploadOptions& o, const Declaration& declared,
                                   bool& ready) {
  v1::ListSurveysRequest list;
  list.set_name(declared.name);
  v1::ListSurveysResponse found;
  check("ListSurveys", surveys.ListSurveys(o.remote.context(30).get(), list, &found));
  if (found.surveys_size() > 0) {
    ready = found.surveys(0).state() == v1::Survey::READY;
    std::fprintf(stderr, "survey %lld '%s' exists%s\n", static_cast<long long>(found.surveys(0).id()), declared.name.c_str(),
                 ready ? " and is ready" : ": resuming its upload");
    return found.surveys(0).id();
  }
  v1::CreateSurveyRequest create;
  create.set_name(declared.name);
  create.set_crs(declared.crs);
  create.set_sonar_json(declared.sonar.dump());
  create.set_vehicle_json(declared.vehicle.dump());
  v1::Survey survey;
  check("CreateSurvey", surveys.CreateSurvey(o.remote.context(30).get(), create, &survey));
  ready = false;
  return survey.id();
}

// Uploads one file from the committed size on; false when stopped by --stop-after-bytes.
bool upload_file(v1::SurveyService::Stub& surveys, const UploadOptions& o, std::int64_t survey_id,
                 const LocalFile& file, std::int64_t& budget, Progress& progress) {
  const std::string& name = file.name;
  const std::int64_t size = file.size;
  const std::string digest = file_sha256(file);

  v1::GetUploadStatusRequest ask;
  ask.set_survey_id(survey_id);
  ask.set_file_name(name);
  v1::UploadStatus status;
  std::int64_t offset = 0;
  const grpc::Status asked = surveys.GetUploadStatus(o.remote.context(30).get(), ask, &status);
  if (asked.ok() && status.size_bytes() == size && status.sha256() == digest) {
    if (status.complete()) {
      progress.say(name + " uploaded already (" + megabytes(size) + ")");
      progress.at(name, size);
      return true;
    }
    offset = status.committed_bytes();
    if (offset > 0) {
      progress.say("resuming " + name + " at " + std::to_string(offset) + " of " + std::to_string(size) + " bytes");
      progress.at(name, offset);
    }
  } else if (!asked.ok() && asked.error_code() != grpc::StatusCode::NOT_FOUND) {
    check("GetUploadStatus", asked);
  }

  auto context = o.remote.context();
  v1::UploadStatus reply;
  auto writer = surveys.UploadFile(context.get(), &reply);
  const std::unique_ptr<ByteSource> in = file.open(static_cast<std::uint64_t>(offset));
  v1::UploadFileRequest message;
  message.set_survey_id(survey_id);
  message.set_file_name(name);
  message.set_size_bytes(size);
  message.set_sha256(digest);
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
    progress.at(name, offset);
  }
  writer->WritesDone();
  const grpc::Status done = writer->Finish();
  check("UploadFile " + name, done);
  if (!reply.complete()) {
    progress.say(name + ": stopped at " + std::to_string(reply.committed_bytes()) + " of " + std::to_string(size) +
                 " bytes; run the same command again to resume");
    return false;
  }
  return true;
}

// A database or server restart costs a pause, not the upload: a call answered UNAVAILABLE is
// made again after a growing pause, for up to --retry-seconds; an upload then resumes from what
// the server has committed (upload_file asks first).
template <typename Step>
auto retrying(const UploadOptions& o, Step&& step) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.retry_seconds);
  for (double pause = 1;; pause = std::min(2 * pause, 15.0)) {
    try {
      return step();
    } catch (const CallFailed& failed) {
      if (failed.code() != grpc::StatusCode::UNAVAILABLE ||
          std::chrono::steady_clock::now() + std::chrono::duration<double>(pause) > give_up)
        throw;
      std::fprintf(stderr, "\n  %s; trying again in %.0f s\n", failed.what(), pause);
      std::this_thread::sleep_for(std::chrono::duration<double>(pause));
    }
  }
}

// Uploads the files side by side, a few at a time (each file's hash, stream and transactions
// beside the others'), or one after another under --stop-after-bytes, whose budget is counted in
// file order. Throws the first failure once the files begun are done.
void upload_files(v1::SurveyService::Stub& surveys, const UploadOptions& o, std::int64_t id,
                  const std::vector<LocalFile>& files) {
  constexpr std::size_t kFilesAtOnce = 4;
  std::int64_t total = 0;
  for (const LocalFile& file : files) total += file.size;
  Progress progress(total);
  std::int64_t budget = o.stop_after_bytes;
  std::atomic<std::size_t> next = 0;
  std::atomic<bool> stopped = false;
  std::mutex failure_mutex;
  std::exception_ptr failure;
  auto work = [&] {
    for (std::size_t k; !stopped && (k = next++) < files.size();) {
      try {
        if (!retrying(o, [&] { return upload_file(surveys, o, id, files[k], budget, progress); }))
          throw std::runtime_error("upload interrupted (--stop-after-bytes)");
      } catch (...) {
        std::lock_guard lock(failure_mutex);
        if (!failure) failure = std::current_exception();
        stopped = true;
      }
    }
  };
  const std::size_t threads = o.stop_after_bytes > 0 ? 1 : std::min(kFilesAtOnce, files.size());
  std::vector<std::thread> workers;
  for (std::size_t t = 1; t < threads; ++t) workers.emplace_back(work);
  work();
  for (std::thread& worker : workers) worker.join();
  progress.end();
  if (failure) std::rethrow_exception(failure);
}

void run_upload(const UploadOptions& o) {
  auto channel = o.remote.channel();
  auto surveys = v1::SurveyService::NewStub(channel);
  // Sonar files of one format: each is a sonar file with the first one's extension.
  const std::string format = lowercase_extension(o.inputs.front());
  const bool sonar = std::all_of(o.inputs.begin(), o.inputs.end(),
                                 [&](const std::string& p) { return is_sonar_file_path(p) && has_extension(p, format); });
  if (!sonar && o.inputs.size() > 1)
    throw std::runtime_error("several inputs must all be sonar files of one format (.gsf, .all or .xtf); a bundle comes alone");
  if (!sonar && (!o.crs.empty() || !o.reference_nav.empty()))
    throw std::runtime_error("--crs and --reference-nav are for sonar files; a bundle has survey.json and reference_nav.csv");
  Declaration declared;
  const std::vector<LocalFile> files = sonar ? sonar_files(o, declared) : bundle_files(o, declared);
  bool ready = false;
  const std::int64_t id = retrying(o, [&] { return find_or_create_survey(*surveys, o, declared, ready); });
  if (!ready) {
    upload_files(*surveys, o, id, files);
    v1::FinalizeSurveyRequest finalize;
    finalize.set_survey_id(id);
    v1::Survey survey;
    retrying(o, [&] { check("FinalizeSurvey", surveys->FinalizeSurvey(o.remote.context(600).get(), finalize, &survey)); });
  }
  std::printf("survey %lld ready\n", static_cast<long long>(id));
}

}  // namespace

void add_upload_command(CLI::App& app) {
  auto o = std::make_shared<UploadOptions>();
  CLI::App* cmd = app.add_subcommand("upload", "Upload a survey (resumes an interrupted upload) and finalize it");
  cmd->add_option("survey", o->inputs, "a survey bundle (a folder or a .tar of one), or one or more .gsf files")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("--crs", o->crs, "GSF: projected CRS of the map frame (default: the data's UTM zone)");
  cmd->add_option("--reference-nav", o->reference_nav, "GSF: reference navigation in the nav.csv format")
      ->check(CLI::ExistingFile);
  cmd->add_option("--name", o->name, "survey name (default: survey.json's name, or the first GSF file's)");
  cmd->add_option("--stop-after-bytes", o->stop_after_bytes, "stop after sending this many bytes, as a cut connection would");
  cmd->add_option("--retry-seconds", o->retry_seconds, "wait out an unavailable server or database this long, then resume")
      ->check(CLI::Range(0.0, 86400.0))
      ->capture_default_str();
  add_remote_options(cmd, o->remote);
  cmd->callback([o] { run_upload(*o); });
}

}  // namespace bathyslam::cli
