#include "server/storage/stored_bundle.h"

#include "core/io/bundle_files.h"
#include "core/io/survey_input.h"
#include "server/scratch_dir.h"

#include <algorithm>
#include <array>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>

namespace bathyslam::storage {
namespace {

constexpr std::array<std::string_view, 4> kBundleFiles = {kSurveyJsonFile, kNavFile, kPingsFile, kReferenceNavFile};

}  // namespace

bool is_bundle_file(const std::string& name) {
  for (std::string_view file : kBundleFiles)
    if (file == name) return true;
  return is_sonar_file_name(name);
}

namespace {

// Sonar-file uploads (GSF, EM .all or XTF): the files in the time order of their first pings,
// reference_nav.csv when uploaded; name, CRS (empty: the data's UTM zone), sonar and vehicle from
// CreateSurvey. A damaged file is one problem naming the file and where in it. The pings go to
// `sink` (the files read twice, the soundings never held whole) and the survey comes back without
// them.
BundleReadResult read_sonar_survey(const SurveyRecord& record, const std::filesystem::path& dir, PingSink& sink) {
  SurveyInput input{{}, record.crs, std::nullopt, false};
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (is_sonar_file_path(entry.path())) input.paths.push_back(entry.path());
  if (std::filesystem::exists(dir / kReferenceNavFile)) input.reference_nav = dir / kReferenceNavFile;
  BundleReadResult result;
  try {
    input.paths = sonar_files_in_time_order(std::move(input.paths));
    Survey survey = read_sonar_navigation(input).survey;
    survey.metadata.name = record.name;
    if (!record.sonar.empty()) survey.metadata.sonar["declared"] = record.sonar;
    survey.metadata.vehicle = record.vehicle;
    stream_sonar_soundings(input, survey, sink);
    result.survey = std::move(survey);
  } catch (const std::exception& e) {
    // Paths in the message are the scratch copy's; the file names are the upload's.
    result.problems.push_back({Problem::Severity::kError, "", 0, "", server::without_folder(e.what(), dir)});
  }
  return result;
}

// A stored file opened when first read: core's bundle reader takes an error while opening for a
// problem of the bundle, and a database outage there is none (the job is given back to the queue,
// the finalize answered UNAVAILABLE); errors while reading reach the reader's caller as they are.
class OpenedWhenRead : public ByteSource {
 public:
  OpenedWhenRead(SurveyStore& store, std::int64_t survey_id, std::string name)
      : store_(store), survey_id_(survey_id), name_(std::move(name)) {}
  std::size_t read(char* buffer, std::size_t size) override {
    if (!file_) file_ = store_.open_file(survey_id_, name_);
    return file_->read(buffer, size);
  }

 private:
  SurveyStore& store_;
  std::int64_t survey_id_;
  std::string name_;
  std::unique_ptr<ByteSource> file_;
};

// A survey's complete uploaded bundle files, read from the database.
class StoredBundle : public BundleSource {
 public:
  StoredBundle(SurveyStore& store, std::int64_t survey_id, const std::vector<std::string>& complete)
      : store_(store), survey_id_(survey_id), complete_(complete) {}
  bool contains(std::string_view file) const override {
    return std::find(complete_.begin(), complete_.end(), file) != complete_.end();
  }
  std::unique_ptr<ByteSource> open(std::string_view file) const override {
    return std::make_unique<OpenedWhenRead>(store_, survey_id_, std::string(file));
  }
  std::string name() const override { return "the upload"; }

 private:
  SurveyStore& store_;
  std::int64_t survey_id_;
  const std::vector<std::string>& complete_;
};

}  // namespace

StoredSurvey::StoredSurvey(SurveyStore& store, std::int64_t survey_id, const std::filesystem::path& scratch_root)
    : store_(store), survey_id_(survey_id) {
  const std::vector<UploadState> uploads = store.uploads(survey_id);
  for (const UploadState& upload : uploads)
    if (upload.complete && is_bundle_file(upload.name)) bundle_files_.push_back(upload.name);
  const bool sonar_files =
      std::any_of(uploads.begin(), uploads.end(), [](const UploadState& upload) { return is_sonar_file_path(upload.name); });
  if (!sonar_files) return;
  std::optional<SurveyRecord> record = store.survey(survey_id);
  if (!record) throw std::runtime_error("survey " + std::to_string(survey_id) + " does not exist");
  record_ = std::move(*record);
  copy_.emplace(scratch_root, "bundle");
  for (const std::string& name : bundle_files_) store.export_file(survey_id, name, copy_->path() / name);
}

BundleReadResult StoredSurvey::read(PingSink& sink) const {
  if (copy_) return read_sonar_survey(record_, copy_->path(), sink);
  return stream_bundle(StoredBundle(store_, survey_id_, bundle_files_), sink);
}

}  // namespace bathyslam::storage
