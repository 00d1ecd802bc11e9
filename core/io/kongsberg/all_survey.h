#pragma once
// Kongsberg EM .all files as a bathyslam Survey (docs/formats.md, "Kongsberg .all in").
//
// Each XYZ 88 swath gives soundings relative to the active positioning system's reference point
// and the transmit transducer, in a level frame along the heading; its navigation sample is the
// active system's position fixes interpolated at the ping, the swath's own heading and transducer
// depth, and the motion sensor's roll and pitch at the ping. As for GSF, roll and pitch are taken
// back out of the beams so that the georef stage, putting them in again, lands every sounding
// where the sonar put it. Swaths outside the span of the position fixes are counted, not kept.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/bundle.h"
#include "core/io/sonar_read.h"
#include "core/types/survey.h"

namespace bathyslam::kongsberg {

// What one .all file held.
struct FileSummary {
  std::string file;
  int model = 0;  // EM model number, e.g. 2040
  std::uint64_t bytes = 0, datagrams = 0;
  std::uint64_t swaths = 0;  // XYZ 88 datagrams
  std::vector<int> heads;    // serial numbers of the sonar heads that wrote them
  std::uint64_t beams = 0, soundings = 0, rejected_beams = 0;
  std::uint64_t swaths_outside_navigation = 0;
  std::uint64_t positions = 0, positions_used = 0;  // used: of the active positioning system
  std::uint64_t attitude_samples = 0;
  bool installation = false;
  std::uint64_t sound_speed_profiles = 0;
  std::uint64_t skipped_datagrams = 0;  // types bathyslam does not decode
  double time_begin = 0, time_end = 0;  // of the swaths
  double latitude_min = 0, latitude_max = 0, longitude_min = 0, longitude_max = 0;  // of the fixes
  double depth_min_m = 0, depth_max_m = 0;  // of the soundings, below the water level
};

nlohmann::json to_json(const FileSummary& summary);
std::string to_text(const FileSummary& summary);

using ReadOptions = SonarReadOptions;
using SurveyRead = SonarRead<FileSummary>;

// Reads `files` (in time order) into one survey; throws AllError for a damaged file,
// std::runtime_error for swaths out of time order, no usable swath or an unusable CRS.
SurveyRead read_survey(const std::vector<std::filesystem::path>& files, const ReadOptions& options = {});

// The soundings of `files` handed to `sink` ping by ping as the files are read again, as
// gsf::stream_soundings does: `survey` is read_survey's of the same files without soundings.
void stream_soundings(const std::vector<std::filesystem::path>& files, Survey& survey, PingSink& sink);

// The time of the file's first XYZ 88 swath, nothing without one; reads the file up to it.
std::optional<double> first_swath_time(const std::filesystem::path& path);

// Whether `path` names an EM .all file (by its extension).
bool is_all_path(const std::filesystem::path& path);

}  // namespace bathyslam::kongsberg
