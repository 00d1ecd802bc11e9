#pragma once
// A survey's uploaded files read as a bundle, by core's bundle reader as it reads one on disk:
// straight from the database, or through a scratch copy (checksums verified, removed when done)
// for sonar files.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/io/bundle.h"
#include "server/scratch_dir.h"
#include "server/storage/survey_store.h"

namespace bathyslam::storage {

// The files a survey may hold: a bundle's, or sonar files of one format (plain names ending in
// .gsf, .all or .xtf) with an optional reference_nav.csv; others are refused at upload.
bool is_bundle_file(const std::string& name);

// A survey's uploaded files, read as often as its reader asks: a job streams the pings into its
// submaps, then again into the corrected GSF, never holding the soundings whole. A bundle is read
// straight from the database each time (each file streamed chunk by chunk, its checksum verified
// at its end, the database's reading beside the parsing); sonar files are copied to a scratch
// folder once, for as long as this lives, as their readers seek in files. Problems name the
// upload's files, never a scratch path.
class StoredSurvey {
 public:
  // Throws what the store throws (a transient database error may be retried), and WriteError
  // when the scratch disk refuses a sonar file's copy.
  StoredSurvey(SurveyStore& store, std::int64_t survey_id, const std::filesystem::path& scratch_root);

  // The bundle (missing files are reported as problems by the reader, with the file name), or the
  // sonar files when the survey has any, its pings handed to `sink`: the survey comes back without
  // them. A database error while reading is thrown, never taken for a problem of the survey.
  BundleReadResult read(PingSink& sink) const;

 private:
  SurveyStore& store_;
  std::int64_t survey_id_;
  std::vector<std::string> bundle_files_;    // the complete ones
  std::optional<server::ScratchDir> copy_;   // sonar-file uploads only
  SurveyRecord record_;  // sonar-file uploads: name, CRS, sonar and vehicle from CreateSurvey
};

}  // namespace bathyslam::storage
