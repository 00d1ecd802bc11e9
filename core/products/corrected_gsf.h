#pragma once
// The survey's pings with the SLAM-corrected navigation as one GSF file: what `bathyslam process
// --export-gsf` writes for a bundle and the service stores as a job product. The writer takes
// any survey, so a survey read from GSF is written this way too (one file, the subset the
// writer knows; `process` keeps every record of GSF input instead, file by file).
#include <cstdint>
#include <filesystem>

#include "core/pipeline/pipeline.h"

namespace bathyslam {

inline constexpr const char* kCorrectedGsfFile = "corrected.gsf";

// Returns how many pings were written (pings outside the corrected navigation are left out).
std::uint64_t write_corrected_gsf(const Survey& survey, const PipelineResult& result, const std::filesystem::path& path);

// The same for a survey read from `bundle` without its soundings (load_survey with a sink):
// the pings are streamed from the bundle again. Throws when the bundle no longer reads.
std::uint64_t write_corrected_gsf(const std::filesystem::path& bundle, const Survey& survey, const PipelineResult& result,
                                  const std::filesystem::path& path);

}  // namespace bathyslam
