#include "core/io/gsf/gsf_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/io/gsf/big_endian.h"

namespace bathyslam::gsf {
namespace {

constexpr std::size_t kFramingBytes = 8;  // size and identifier

std::string hex(std::uint32_t v) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "0x%08x", v);
  return buffer;
}

// How one decoded beam array is stored (Table 4-3): the field sizes it may have and its sign.
struct ArrayKind {
  const char* name;
  std::uint8_t widths;  // bit mask: 1, 2 or 4 bytes
  bool is_signed;
};

ArrayKind array_kind(std::uint8_t id) {
  switch (id) {
    case kDepthArray: return {"depth", 2 | 4, false};
    case kAcrossTrackArray: return {"across-track", 2 | 4, true};
    case kAlongTrackArray: return {"along-track", 2 | 4, true};
    case kTravelTimeArray: return {"travel-time", 2 | 4, false};
    case kBeamAngleArray: return {"beam-angle", 2, true};
    default: return {"?", 0, false};
  }
}

// The field size of a scaled array: the scale factor's compression flag when it says, otherwise
// what the subrecord's size implies (writers leave the flag 0 for the default size).
int field_width(const ScaleFactor& scale, std::size_t size, int num_beams) {
  switch (scale.compression & 0xf0) {
    case 0x10: return 1;
    case 0x20: return 2;
    case 0x40: return 4;
    default: break;
  }
  if (num_beams == 0 || size % static_cast<std::size_t>(num_beams) != 0) return 0;
  return static_cast<int>(size / static_cast<std::size_t>(num_beams));
}

}  // namespace

GsfError::GsfError(const std::string& file, std::uint64_t record, std::uint64_t offset, const std::string& what)
    : std::runtime_error(file + ": record " + std::to_string(record) + " at byte " + std::to_string(offset) + ": " +
                         what),
      record_(record),
      offset_(offset) {}

Reader::Reader(ByteSource& source, std::string file) : source_(source), file_(std::move(file)) {}

void Reader::fail(std::uint64_t offset, const std::string& what) const {
  throw GsfError(file_, record_number_, offset, what);
}

std::optional<Record> Reader::next() {
  const std::uint64_t record_offset = offset_;
  std::uint8_t framing[kFramingBytes];
  const std::size_t got = read_fully(source_, reinterpret_cast<char*>(framing), kFramingBytes);
  ++record_number_;
  if (got == 0) {
    if (record_number_ == 1) fail(record_offset, "empty file, not GSF");
    --record_number_;
    return std::nullopt;
  }
  if (got < kFramingBytes) {
    fail(record_offset, "truncated: the file ends " + std::to_string(got) + " bytes into a record's 8-byte framing");
  }
  BigEndianCursor cursor(std::span<const std::uint8_t>(framing, kFramingBytes));
  const std::uint32_t size = cursor.u32();
  const std::uint32_t id = cursor.u32();
  id_ = id;
  const bool has_checksum = (id >> 31) != 0;
  const std::uint32_t reserved = (id >> 22) & 0x1ff;
  const std::uint32_t registry = (id >> 12) & 0x3ff;
  const std::uint32_t type = id & 0xfff;

  if (record_number_ == 1 && (registry != 0 || type != kHeader || reserved != 0)) {
    fail(record_offset, "not a GSF file: the first record's identifier is " + hex(id) +
                            ", a GSF file starts with the header record (1)");
  }
  if (reserved != 0) fail(record_offset + 4, "identifier " + hex(id) + " has reserved bits set");
  if (registry == 0 && (type == 0 || type > kLastRecordId)) {
    fail(record_offset + 4, "unknown record id " + std::to_string(type) + " (identifier " + hex(id) + ")");
  }
  if (size % 4 != 0) fail(record_offset, "record size " + std::to_string(size) + " is not a multiple of 4");
  if (size > kMaxRecordBytes) {
    fail(record_offset, "record size " + std::to_string(size) + " exceeds the " + std::to_string(kMaxRecordBytes) +
                            "-byte limit");
  }
  std::uint64_t data_offset = record_offset + kFramingBytes;
  std::uint32_t checksum = 0;
  if (has_checksum) {
    std::uint8_t word[4];
    if (read_fully(source_, reinterpret_cast<char*>(word), 4) < 4) {
      fail(data_offset, "truncated: the file ends inside the record's checksum");
    }
    checksum = BigEndianCursor(std::span<const std::uint8_t>(word, 4)).u32();
    data_offset += 4;
  }
  if (const std::size_t got = read_record(source_, size, data_); got < size) {
    fail(record_offset, "truncated: the record declares " + std::to_string(size) + " data bytes but the file ends after " +
                            std::to_string(got));
  }
  offset_ = data_offset + size;
  if (has_checksum) {
    std::uint32_t sum = 0;
    for (std::uint8_t b : data_) sum += b;
    if (sum != checksum) fail(data_offset, "checksum " + hex(sum) + " differs from the recorded " + hex(checksum));
  }
  try {
    return decode(registry, type, data_offset);
  } catch (const OutOfBounds& e) {
    fail(data_offset + e.position(), e.what());
  }
}

Record Reader::decode(std::uint32_t registry, std::uint32_t type, std::uint64_t data_offset) {
  BigEndianCursor c(data_);
  if (registry != 0) return Skipped{registry, type};
  switch (type) {
    case kHeader: {
      if (record_number_ != 1) fail(data_offset, "a second header record");
      Header h;
      h.version = c.text(c.remaining());
      if (h.version.rfind("GSF-v", 0) != 0 ||
          std::sscanf(h.version.c_str() + 5, "%d.%d", &h.major, &h.minor) != 2) {
        fail(data_offset, "not a GSF file: the header's version is '" + h.version + "', not GSF-vMM.mm");
      }
      header_ = h;
      return h;
    }
    case kSwathBathymetryPing: return decode_ping(data_offset);
    case kSoundVelocityProfile: {
      SoundVelocityProfile svp;
      svp.observed_time = c.time();
      svp.applied_time = c.time();
      svp.longitude_deg = c.i32() * 1e-7;
      svp.latitude_deg = c.i32() * 1e-7;
      const std::int32_t n = c.i32();
      if (n < 0 || static_cast<std::size_t>(n) > c.remaining() / 8) {
        fail(data_offset + 24, "sound velocity profile of " + std::to_string(n) + " points does not fit its record");
      }
      for (std::int32_t i = 0; i < n; ++i) {
        svp.depth_m.push_back(c.u32() * 0.01);
        svp.sound_velocity_m_s.push_back(c.u32() * 0.01);
      }
      return svp;
    }
    case kProcessingParameters: {
      ProcessingParameters p;
      p.time = c.time();
      const std::int16_t n = c.i16();
      if (n < 0) fail(data_offset + 8, "negative number of processing parameters");
      for (std::int16_t i = 0; i < n; ++i) {
        const std::int16_t length = c.i16();
        if (length < 0) fail(data_offset + c.position() - 2, "negative parameter length");
        p.parameters.push_back(c.text(static_cast<std::size_t>(length)));
      }
      return p;
    }
    case kComment: {
      Comment comment;
      comment.time = c.time();
      const std::uint32_t length = c.u32();
      comment.text = c.text(length);
      return comment;
    }
    case kAttitude: {
      Attitude a;
      const double base = c.time();
      const std::int16_t n = c.i16();
      if (n < 0) fail(data_offset + 8, "negative number of attitude measurements");
      const auto count = static_cast<std::size_t>(n);
      if (count * 10 > c.remaining()) {
        fail(data_offset + 8, std::to_string(n) + " attitude measurements do not fit the record");
      }
      a.time.resize(count);
      a.pitch_deg.resize(count);
      a.roll_deg.resize(count);
      a.heave_m.resize(count);
      a.heading_deg.resize(count);
      // Times are millisecond offsets from the base time; angles hundredths of degrees; heave cm.
      for (double& t : a.time) t = base + c.i16() * 1e-3;
      for (double& v : a.pitch_deg) v = c.i16() * 0.01;
      for (double& v : a.roll_deg) v = c.i16() * 0.01;
      for (double& v : a.heave_m) v = c.i16() * 0.01;
      for (double& v : a.heading_deg) v = c.u16() * 0.01;
      return a;
    }
    default: return Skipped{registry, type};  // sensor parameters, history, summary, ...
  }
}

Ping Reader::decode_ping(std::uint64_t data_offset) {
  if (header_.major == 0) fail(data_offset, "ping before the header");
  BigEndianCursor c(data_);
  Ping p;
  p.time = c.time();
  p.longitude_deg = c.i32() * 1e-7;
  p.latitude_deg = c.i32() * 1e-7;
  p.num_beams = c.i16();
  p.center_beam = c.i16();
  p.flags = c.u16();
  c.skip(2);  // reserved
  // 9999 cm is libgsf's null corrector (GSF_NULL_TIDE_CORRECTOR, GSF_NULL_DEPTH_CORRECTOR):
  // nothing was added to the depths.
  constexpr int kNullCorrectorCm = 9999;
  const std::int16_t tide_cm = c.i16();
  const std::int32_t depth_cm = c.i32();
  p.tide_corrector_m = tide_cm == kNullCorrectorCm ? 0.0 : tide_cm * 0.01;
  p.depth_corrector_m = depth_cm == kNullCorrectorCm ? 0.0 : depth_cm * 0.01;
  p.heading_deg = c.u16() * 0.01;
  p.pitch_deg = c.i16() * 0.01;
  p.roll_deg = c.i16() * 0.01;
  p.heave_m = c.i16() * 0.01;
  p.course_deg = c.u16() * 0.01;
  p.speed_knots = c.u16() * 0.01;
  if (header_.major >= 3 && !(header_.major == 3 && header_.minor < 1)) {
    c.skip(kPingHeaderBytes - kPingHeaderBytesBefore301);  // height, separation, GPS tide, spare
  }
  if (p.num_beams < 0) fail(data_offset + 16, "negative number of beams " + std::to_string(p.num_beams));
  if (std::abs(p.latitude_deg) > 90 || std::abs(p.longitude_deg) > 180) {
    fail(data_offset + 8, "impossible position: longitude " + std::to_string(p.longitude_deg) + ", latitude " +
                              std::to_string(p.latitude_deg));
  }
  const auto n = static_cast<std::size_t>(p.num_beams);

  while (c.remaining() >= 4) {  // fewer is the record's padding
    const std::size_t sub_position = c.position();
    const std::uint32_t word = c.u32();
    const auto id = static_cast<std::uint8_t>(word >> 24);
    std::size_t size = word & 0xffffff;
    // libgsf declares its intensity time-series subrecord (21) a byte longer than it writes
    // (EX1811's pings): a skipped last subrecord may overrun the record by less than a word.
    const bool decoded = id == kScaleFactors || id == kBeamFlagsArray || array_kind(id).widths != 0;
    if (!decoded && size > c.remaining() && size - c.remaining() < 4) size = c.remaining();
    if (size > c.remaining()) {
      fail(data_offset + sub_position, "subrecord " + std::to_string(id) + " of " + std::to_string(size) +
                                           " bytes runs past the end of the ping record");
    }
    BigEndianCursor s = c.sub(size);
    if (id == kScaleFactors) {
      const std::int32_t count = s.i32();
      if (count < 0 || static_cast<std::size_t>(count) > s.remaining() / 12) {
        fail(data_offset + sub_position, std::to_string(count) + " scale factors do not fit their subrecord");
      }
      for (std::int32_t i = 0; i < count; ++i) {
        const std::uint8_t array = s.u8();
        ScaleFactor& f = scales_[array];
        f.present = true;
        f.compression = s.u8();
        s.skip(2);
        f.multiplier = s.i32();
        f.offset = s.i32();
      }
      continue;
    }
    if (id == kBeamFlagsArray) {
      if (size < n) fail(data_offset + sub_position, "beam flags array shorter than its " + std::to_string(n) + " beams");
      p.beam_flags.resize(n);
      for (std::uint8_t& f : p.beam_flags) f = s.u8();
      continue;
    }
    const ArrayKind kind = array_kind(id);
    if (kind.widths == 0) continue;  // an array or sensor-specific subrecord bathyslam does not use
    const ScaleFactor& scale = scales_[id];
    const std::string where = std::string(kind.name) + " array: ";
    if (!scale.present) fail(data_offset + sub_position, where + "no scale factor has been given for it");
    if (scale.multiplier <= 0) {
      fail(data_offset + sub_position, where + "impossible scale factor (multiplier " +
                                           std::to_string(scale.multiplier) + ")");
    }
    const int width = field_width(scale, size, p.num_beams);
    if (n > 0 && (!(width == 2 || width == 4) || (kind.widths & width) == 0 || n * static_cast<std::size_t>(width) > size)) {
      fail(data_offset + sub_position, where + std::to_string(size) + " bytes for " + std::to_string(n) +
                                           " beams is not a valid field size");
    }
    std::vector<double> values(n);
    const double multiplier = scale.multiplier;
    const double offset = scale.offset;
    for (double& v : values) {
      double raw = 0;
      if (width == 2) raw = kind.is_signed ? static_cast<double>(s.i16()) : s.u16();
      else raw = kind.is_signed ? static_cast<double>(s.i32()) : s.u32();
      v = raw / multiplier - offset;
    }
    switch (id) {
      case kDepthArray: p.depth_m = std::move(values); break;
      case kAcrossTrackArray: p.across_m = std::move(values); break;
      case kAlongTrackArray: p.along_m = std::move(values); break;
      case kTravelTimeArray: p.travel_time_s = std::move(values); break;
      case kBeamAngleArray: p.beam_angle_deg = std::move(values); break;
      default: break;
    }
  }
  return p;
}

}  // namespace bathyslam::gsf
