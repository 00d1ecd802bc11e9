#include "server/storage/stored_bundle.h"

#include "server/scratch_dir.h"

#include <array>
#include <fstream>
#include <string_view>

namespace bathyslam::storage {
namespace {

constexpr std::array<std::string_view, 4> kBundleFiles = {kSurveyJsonFile, kNavFile, kPingsFile, kReferenceNavFile};

}  // namespace

bool is_bundle_file(const std::string& name) {
  for (std::string_view file : kBundleFiles)
    if (file == name) return true;
  return false;
}

BundleReadResult read_stored_bundle(SurveyStore& store, std::int64_t survey_id, const std::filesystem::path& scratch_root) {
  server::ScratchDir scratch(scratch_root, "bundle");
  for (const UploadState& upload : store.uploads(survey_id)) {
    if (!upload.complete || !is_bundle_file(upload.name)) continue;
    std::ofstream out(scratch.path() / upload.name, std::ios::binary);
    store.export_file(survey_id, upload.name, out);
  }
  BundleReadResult result = read_bundle(scratch.path());
  // The reader names the folder of a missing file; the scratch folder means nothing to a user.
  const std::string where = " from " + scratch.path().string();
  for (Problem& problem : result.problems)
    if (auto at = problem.message.find(where); at != std::string::npos) problem.message.replace(at, where.size(), " from the upload");
  return result;
}

}  // namespace bathyslam::storage
