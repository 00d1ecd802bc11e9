#pragma once
// A survey's uploaded files read as a bundle: copied into a scratch folder (streamed chunk by
// chunk, checksums verified) so that core's bundle reader parses them exactly as it parses a
// bundle on disk, then the copy is removed.
#include <cstdint>
#include <filesystem>

#include "core/io/bundle.h"
#include "server/storage/survey_store.h"

namespace bathyslam::storage {

// The files a survey may hold: a bundle's, or GSF files (plain names ending in .gsf) with an
// optional reference_nav.csv; others are refused at upload.
bool is_bundle_file(const std::string& name);

// Reads the survey's complete bundle files (missing ones are reported as problems by the
// reader, with the file name and no scratch path), or its GSF files when it has any.
BundleReadResult read_stored_bundle(SurveyStore& store, std::int64_t survey_id, const std::filesystem::path& scratch_root);

}  // namespace bathyslam::storage
