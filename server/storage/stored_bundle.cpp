#include "server/storage/stored_bundle.h"

#include "core/io/bundle_files.h"
#include "core/io/survey_input.h"
#include "server/scratch_dir.h"

#include <algorithm>
#include <array>
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

// A survey's complete uploaded bundle files, read from the database.
class StoredBundle : public BundleSource {
 public:
  StoredBundle(SurveyStore& store, std::int64_t survey_id, const std::vector<UploadState>& uploads)
      : store_(store), survey_id_(survey_id) {
    for (const UploadState& upload : uploads)
      if (upload.complete && is_bundle_file(upload.name)) complete_.push_back(upload.name);
  }
  bool contains(std::string_view file) const override {
    return std::find(complete_.begin(), complete_.end(), file) != complete_.end();
  }
  std::unique_ptr<ByteSource> open(std::string_view file) const override {
    return store_.open_file(survey_id_, std::string(file));
  }
  std::string name() const override { return "the upload"; }

 private:
  SurveyStore& store_;
  std::int64_t survey_id_;
  std::vector<std::string> complete_;
};

}  // namespace

BundleReadResult read_stored_survey(SurveyStore& store, std::int64_t survey_id, const std::filesystem::path& scratch_root,
                                    PingSink& sink) {
  const std::vector<UploadState> uploads = store.uploads(survey_id);
  const bool sonar_files =
      std::any_of(uploads.begin(), uploads.end(), [](const UploadState& upload) { return is_sonar_file_path(upload.name); });
  if (sonar_files) return StoredSurveyCopy(store, survey_id, scratch_root).read(sink);
  return stream_bundle(StoredBundle(store, survey_id, uploads), sink);
}

StoredSurveyCopy::StoredSurveyCopy(SurveyStore& store, std::int64_t survey_id, const std::filesystem::path& scratch_root)
    : scratch_(scratch_root, "bundle") {
  for (const UploadState& upload : store.uploads(survey_id)) {
    sonar_files_ = sonar_files_ || is_sonar_file_path(upload.name);
    if (!upload.complete || !is_bundle_file(upload.name)) continue;
    store.export_file(survey_id, upload.name, scratch_.path() / upload.name);
  }
  if (sonar_files_) {
    std::optional<SurveyRecord> record = store.survey(survey_id);
    if (!record) throw std::runtime_error("survey " + std::to_string(survey_id) + " does not exist");
    record_ = std::move(*record);
  }
}

BundleReadResult StoredSurveyCopy::read(PingSink& sink) const {
  if (sonar_files_) return read_sonar_survey(record_, scratch_.path(), sink);
  return named_as_upload(stream_bundle(scratch_.path(), sink));
}

// The reader names the folder of a missing file; the scratch folder means nothing to a user.
BundleReadResult StoredSurveyCopy::named_as_upload(BundleReadResult result) const {
  const std::string where = " from " + scratch_.path().string();
  for (Problem& problem : result.problems)
    if (auto at = problem.message.find(where); at != std::string::npos) problem.message.replace(at, where.size(), " from the upload");
  return result;
}

}  // namespace bathyslam::storage
