#pragma once
// A survey's uploaded files read as a bundle, by core's bundle reader as it reads one on disk:
// straight from the database for a validation, or through a scratch copy (checksums verified,
// removed when done) for a job, which reads them twice, and for sonar files.
#include <cstdint>
#include <filesystem>

#include "core/io/bundle.h"
#include "server/scratch_dir.h"
#include "server/storage/survey_store.h"

namespace bathyslam::storage {

// The files a survey may hold: a bundle's, or sonar files of one format (plain names ending in
// .gsf, .all or .xtf) with an optional reference_nav.csv; others are refused at upload.
bool is_bundle_file(const std::string& name);

// A survey's uploaded files read once, its pings handed to `sink`: a bundle straight from the
// database (each file streamed chunk by chunk, its checksum verified at its end, the database's
// reading beside the parsing), sonar files through a scratch copy, as their readers need files.
// Problems name the upload's files, never a scratch path. For a validation.
BundleReadResult read_stored_survey(SurveyStore& store, std::int64_t survey_id, const std::filesystem::path& scratch_root,
                                    PingSink& sink);

// A survey's complete uploaded files copied into a scratch folder for as long as this lives, so
// that they can be read more than once: a job streams the pings into its submaps, then again
// into the corrected GSF, never holding the soundings whole.
class StoredSurveyCopy {
 public:
  // Throws what the store throws (a transient database error may be retried).
  StoredSurveyCopy(SurveyStore& store, std::int64_t survey_id, const std::filesystem::path& scratch_root);

  // The bundle (missing files are reported as problems by the reader, with the file name and no
  // scratch path), or the sonar files when the survey has any, its pings handed to `sink`: the
  // survey comes back without them. Neither is held whole: a bundle streams, sonar files are read
  // twice (the navigation and every error, then the soundings).
  BundleReadResult read(PingSink& sink) const;

 private:
  BundleReadResult named_as_upload(BundleReadResult result) const;

  server::ScratchDir scratch_;
  bool sonar_files_ = false;
  SurveyRecord record_;  // sonar-file uploads: name, CRS, sonar and vehicle from CreateSurvey
};


}  // namespace bathyslam::storage
