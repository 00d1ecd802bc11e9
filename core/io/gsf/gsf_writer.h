#pragma once
// Streaming GSF writer for the subset the reader decodes: the header, comments, processing
// parameters and swath bathymetry pings (depth, across-track, along-track, beam flags, and
// travel time and beam angle when the ping has them). Records are written as they come, so a
// survey of any size needs the memory of one ping.
//
// Fixed scale factors, written with the first ping (section 4.3.4.2): depth, across- and
// along-track 4-byte integers of tenths of a millimetre; travel time 4-byte microseconds; beam angle
// 2-byte hundredths of a degree. The file appears under its name only once closed.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/io/gsf/gsf_records.h"

namespace bathyslam::gsf {

inline constexpr const char* kWrittenVersion = "GSF-v03.11";

class Writer {
 public:
  // Starts `path` (under a temporary name) with the header record of `version`; throws
  // std::runtime_error naming the path when it cannot.
  explicit Writer(const std::filesystem::path& path, const std::string& version = kWrittenVersion);
  ~Writer();  // an unclosed writer removes its temporary file
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  void write(const Comment& comment);
  void write(const ProcessingParameters& parameters);
  // Throws std::runtime_error naming the ping when a value does not fit its field.
  void write(const Ping& ping);
  // A record as another file stored it (`id` as its identifier word, checksum recomputed when
  // flagged): copies what this writer does not decode.
  void write_raw(std::uint32_t id, std::vector<std::uint8_t> data);
  // Flushes and renames the file into place.
  void close();

  std::uint64_t pings_written() const { return pings_; }

 private:
  void write_record(std::uint32_t id, std::vector<std::uint8_t>& data);

  std::filesystem::path path_, temporary_;
  std::ofstream out_;
  std::uint64_t pings_ = 0;
  bool closed_ = false;
  // Which arrays the scale-factor subrecord last written covers (they apply until replaced).
  std::vector<std::uint8_t> scaled_arrays_;
};

}  // namespace bathyslam::gsf
