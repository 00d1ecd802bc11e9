#pragma once
// XTF multibeam files (R2Sonic bathymetry as QINSy logs it) as a bathyslam Survey
// (docs/formats.md, "XTF in").
//
// Each ping's navigation sample is the position packets' fixes interpolated at the ping, and the
// attitude packets' heading, roll, pitch and heave there (without such packets: what the logger
// wrote into the ping header). Its soundings are the beams' two-way times at the array's sound
// speed along straight rays at their angles across the array, turned by the bathymetry channel's
// mounting angles and moved by its offsets: positions in the vessel frame, which the georef stage
// turns by the ping's roll, pitch and heading. The vessel's reference point is at the channel
// offsets' origin, `ReferencePointHeight` above the water line, and moves with the heave (positive
// up). Pings outside the span of the fixes, or more than a second from the attitude, are counted,
// not kept.
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/bundle.h"
#include "core/io/sonar_read.h"
#include "core/types/survey.h"

namespace bathyslam::xtf {

// What one XTF file held.
struct FileSummary {
  std::string file;
  std::string recording_program, sonar;  // e.g. "QINSy", "R2Sonic 2026"
  std::uint64_t bytes = 0, packets = 0;
  std::map<int, std::uint64_t> packets_by_type;
  std::uint64_t pings = 0, beams = 0, soundings = 0, rejected_beams = 0;
  std::uint64_t pings_outside_navigation = 0;
  std::uint64_t positions = 0, attitude_samples = 0;
  bool navigation_from_ping_headers = false;
  double time_begin = 0, time_end = 0;  // of the pings
  double latitude_min = 0, latitude_max = 0, longitude_min = 0, longitude_max = 0;  // of the fixes
  double range_min_m = 0, range_max_m = 0;  // slant ranges of the soundings
};

nlohmann::json to_json(const FileSummary& summary);
std::string to_text(const FileSummary& summary);

using ReadOptions = SonarReadOptions;
using SurveyRead = SonarRead<FileSummary>;

// Reads `files` (in time order) into one survey; throws XtfError for a damaged file,
// std::runtime_error for pings out of time order, no usable ping or an unusable CRS.
SurveyRead read_survey(const std::vector<std::filesystem::path>& files, const ReadOptions& options = {});

// The soundings of `files` handed to `sink` ping by ping as the files are read again
// (gsf::stream_soundings): `survey` is read_survey's of the same files without soundings.
void stream_soundings(const std::vector<std::filesystem::path>& files, Survey& survey, PingSink& sink);

// The time of the file's first bathymetry ping, nothing without one; reads the file up to it.
std::optional<double> first_ping_time(const std::filesystem::path& path);

// Whether `path` names an XTF file (by its extension).
bool is_xtf_path(const std::filesystem::path& path);

}  // namespace bathyslam::xtf
