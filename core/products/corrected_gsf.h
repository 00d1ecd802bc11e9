#pragma once
// The survey's pings with the SLAM-corrected navigation as one GSF file: what `bathyslam process
// --export-gsf` writes for a bundle and the service stores as a job product. The writer takes
// any survey, so a survey read from GSF is written this way too (one file, the subset the
// writer knows; `process` keeps every record of GSF input instead, file by file).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "core/io/bundle.h"
#include "core/pipeline/pipeline.h"

namespace bathyslam {

inline constexpr const char* kCorrectedGsfFile = "corrected.gsf";
// A job of several surveys: the first survey's is corrected.gsf, the k-th's (k = 2..N)
// corrected.<k>.gsf, as its trajectory is trajectory.<k>.csv.
std::string corrected_gsf_name(int survey_number);

// The pings that `read_pings` hands on (the survey's files read again: `survey` was read
// without its soundings), with the corrected navigation. `read_pings` is stream_bundle for a
// bundle, or the service's stored copy; a survey that no longer reads throws BundleError.
// Returns how many pings were written (pings outside the corrected navigation are left out).
// `survey_index`: the survey's place in a job of several (0: the first, or the only one).
std::uint64_t write_corrected_gsf(const Survey& survey, const PipelineResult& result, const std::filesystem::path& path,
                                  const std::function<BundleReadResult(PingSink&)>& read_pings, int survey_index = 0);

}  // namespace bathyslam
