#pragma once
// Streaming GSF reader: one record at a time from a ByteSource, so a file of any size is read in
// the memory of its largest record (itself bounded). Framing (section 4.3.1): a 4-byte data size,
// a 4-byte identifier (checksum flag, 9 reserved bits, 10-bit registry, 12-bit type), an optional
// checksum, then the data padded to a multiple of 4 bytes; everything big-endian.
//
// Damaged input never crashes or hangs the reader: every problem is a GsfError naming the file,
// the record's number (1-based) and the byte offset of the fault.
#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/io/byte_source.h"
#include "core/io/gsf/gsf_records.h"

namespace bathyslam::gsf {

// No real record comes near this (a 432-beam EM302 ping with intensity series is 28 KB); a
// larger declared size is damage, refused before anything is allocated for it.
inline constexpr std::uint32_t kMaxRecordBytes = 64u << 20;

class GsfError : public std::runtime_error {
 public:
  GsfError(const std::string& file, std::uint64_t record, std::uint64_t offset, const std::string& what);
  std::uint64_t record() const { return record_; }
  std::uint64_t offset() const { return offset_; }

 private:
  std::uint64_t record_;
  std::uint64_t offset_;
};

// How a ping's array subrecords are scaled (section 4.3.4.2): stored = (value + offset) * multiplier.
struct ScaleFactor {
  bool present = false;
  std::uint8_t compression = 0;  // high nibble: field size (0x10 one, 0x20 two, 0x40 four bytes)
  std::int32_t multiplier = 0;
  std::int32_t offset = 0;
};

class Reader {
 public:
  // `file` names the input in errors.
  Reader(ByteSource& source, std::string file);

  // The next record, or nothing at the end of the file. The first record must be the header.
  std::optional<Record> next();

  std::uint64_t records_read() const { return record_number_; }
  std::uint64_t bytes_read() const { return offset_; }
  // The last record as stored: its identifier word and its data (without framing or checksum),
  // for tools that copy records through unchanged.
  std::uint32_t record_id() const { return id_; }
  const std::vector<std::uint8_t>& record_data() const { return data_; }
  const Header& header() const { return header_; }

 private:
  Record decode(std::uint32_t registry, std::uint32_t type, std::uint64_t data_offset);
  Ping decode_ping(std::uint64_t data_offset);
  [[noreturn]] void fail(std::uint64_t offset, const std::string& what) const;

  ByteSource& source_;
  std::string file_;
  std::uint64_t offset_ = 0;         // of the next record
  std::uint64_t record_number_ = 0;  // of the record being read
  std::uint32_t id_ = 0;             // the current record's identifier word
  std::vector<std::uint8_t> data_;   // the current record's data, reused
  Header header_;
  // Scale factors apply from the ping that carries them until replaced (section 4.3.4).
  std::array<ScaleFactor, 256> scales_{};
};

}  // namespace bathyslam::gsf
