#pragma once
// GSF files as a bathyslam Survey, and a Survey's pings as a GSF file.
//
// Reading (docs/formats.md, "GSF in"): every ping header gives a navigation sample (latitude/longitude
// projected into the survey's CRS, depth corrector as vehicle depth, roll, pitch, heading);
// every usable beam of a usable ping gives a sounding in the vehicle frame. GSF stores beams
// in a level frame aligned with the heading (attitude already applied), so the reader takes
// roll and pitch back out: the georef stage puts them in again, and each sounding lands where
// the GSF file has it. Ignored pings and rejected beams are counted, not kept.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/bundle.h"
#include "core/io/sonar_read.h"
#include "core/io/byte_source.h"
#include "core/io/crs.h"
#include "core/types/survey.h"

namespace bathyslam::gsf {

// What one GSF file held.
struct FileSummary {
  std::string file;
  std::string version;
  std::uint64_t bytes = 0;
  std::uint64_t records = 0;
  std::uint64_t pings = 0;
  std::uint64_t ignored_pings = 0;   // ping flag bit 0
  std::uint64_t beams = 0;           // in usable pings
  std::uint64_t soundings = 0;       // usable beams of usable pings
  std::uint64_t rejected_beams = 0;  // beam flag bit 0, or without depth/across-track
  int max_beams_per_ping = 0, min_beams_per_ping = 0;
  std::uint64_t attitude_records = 0, attitude_samples = 0;
  std::uint64_t sound_velocity_profiles = 0;
  std::uint64_t processing_parameter_records = 0;
  std::uint64_t comments = 0;
  std::uint64_t skipped_records = 0;  // records bathyslam does not decode
  double time_begin = 0, time_end = 0;
  double latitude_min = 0, latitude_max = 0, longitude_min = 0, longitude_max = 0;
  double depth_min_m = 0, depth_max_m = 0;  // of the soundings
};

nlohmann::json to_json(const FileSummary& summary);
std::string to_text(const FileSummary& summary);

using ReadOptions = SonarReadOptions;
using SurveyRead = SonarRead<FileSummary>;

// Reads `files` (in time order) into one survey; throws GsfError for a damaged file,
// std::runtime_error for pings out of time order or an unusable CRS.
SurveyRead read_survey(const std::vector<std::filesystem::path>& files, const ReadOptions& options = {});

// The soundings of `files` handed to `sink` ping by ping as the files are read again, never held
// whole: `survey` is what read_survey made of the same files without soundings (keep_soundings
// false), so every error has been found before the sink sees a ping, and its metadata is what
// the sink is to see. Its pings are checked against the files' (a file that changed in between
// throws std::runtime_error) and freed: it comes back as stream_bundle's does.
void stream_soundings(const std::vector<std::filesystem::path>& files, Survey& survey, PingSink& sink);

// The time of the file's first ping, nothing without one; reads the file up to it.
std::optional<double> first_ping_time(const std::filesystem::path& path);

// The summary of one file alone, without building a survey (constant memory).
FileSummary summarize_file(ByteSource& source, const std::string& file);

// Writes the pings of `survey` as GSF with the navigation `nav` (the survey's own, or a
// corrected one; the CRS is the survey's) interpolated at each ping: the inverse of read_survey.
// Pings outside `nav`'s span are left out; returns how many were written.
std::uint64_t write_survey(const Survey& survey, const std::vector<NavSample>& nav,
                           const std::filesystem::path& path);

class Writer;

// write_survey a ping at a time, for pings streamed from a bundle (stream_bundle) instead of
// held: begin() takes the survey's name and CRS, close() finishes the file and returns how many
// pings it holds. Unclosed, the file is not created.
class SurveyWriter : public PingSink {
 public:
  SurveyWriter(const std::filesystem::path& path, std::vector<NavSample> nav);
  ~SurveyWriter() override;
  void begin(const Survey& survey) override;
  void ping(double time, std::span<const Beam> beams) override;
  std::uint64_t close();

 private:
  void write_comment(double time);  // the first record after the header, at the first ping's time

  std::vector<NavSample> nav_;
  std::unique_ptr<Writer> writer_;
  std::unique_ptr<GeographicProjection> projection_;
  std::string comment_;
  bool commented_ = false;
};

// Whether `path` names a GSF file (by its extension, as the tools that write it name them).
bool is_gsf_path(const std::filesystem::path& path);


}  // namespace bathyslam::gsf
