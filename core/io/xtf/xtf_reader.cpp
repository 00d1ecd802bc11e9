#include <cmath>

#include "core/io/binary_fields.h"
#include "core/io/xtf/xtf_packets.h"
#include "core/types/format.h"

namespace bathyslam::xtf {
namespace {

constexpr std::size_t kFileHeaderBytes = 1024, kChannelBytes = 128, kPacketHeaderBytes = 14;
constexpr std::size_t kPingHeaderBytes = 256 - kPacketHeaderBytes;  // the XTF ping header after the packet header
constexpr std::uint8_t kFileFormat = 123;
constexpr std::uint16_t kPacketMagic = 0xFACE;
constexpr std::uint32_t kBth0 = 0x42544830;  // "BTH0"
constexpr int kBathymetryChannel = 3;

std::uint16_t section(char a, char b) { return static_cast<std::uint16_t>((a << 8) | b); }

double epoch_seconds(int year, int month, int day, int hour, int minute, int second, double fraction) {
  if (year < 1980 || year > 2200 || month < 1 || month > 12 || day < 1 || day > 31) {
    throw BadField{"date", std::to_string(year) + "-" + std::to_string(month) + "-" + std::to_string(day) + " is not a date"};
  }
  if (hour > 23 || minute > 59 || second > 60) {
    throw BadField{"time", std::to_string(hour) + ":" + std::to_string(minute) + ":" + std::to_string(second) + " is not a time of day"};
  }
  return static_cast<double>(days_from_civil(year, month, day)) * 86400.0 + hour * 3600.0 + minute * 60.0 + second + fraction;
}

// Year, month, day, hour, minute, second as XTF writes them (u16, then five u8).
double date_time(FieldCursor& c, double fraction_unit, bool fraction_u16) {
  const int year = c.u16("year");
  const int month = c.u8("month"), day = c.u8("day"), hour = c.u8("hour"), minute = c.u8("minute"), second = c.u8("second");
  const double fraction = (fraction_u16 ? c.u16("fraction of a second") : c.u8("fraction of a second")) * fraction_unit;
  if (fraction >= 1.0) throw BadField{"fraction of a second", std::to_string(fraction) + " s is a second or more"};
  return epoch_seconds(year, month, day, hour, minute, second, fraction);
}

double finite(double v, const char* field, double limit) {
  if (!std::isfinite(v) || std::abs(v) > limit) throw BadField{field, std::to_string(v) + " is out of range"};
  return v;
}

Mounting mounting(FieldCursor& c) {
  c.skip(48 - 28, "channel settings");
  Mounting m;
  m.starboard_m = finite(c.f32("OffsetX"), "OffsetX", 1000);
  m.forward_m = finite(c.f32("OffsetY"), "OffsetY", 1000);
  m.down_m = finite(c.f32("OffsetZ"), "OffsetZ", 1000);
  m.yaw_deg = finite(c.f32("OffsetYaw"), "OffsetYaw", 360);
  m.pitch_deg = finite(c.f32("OffsetPitch"), "OffsetPitch", 360);
  m.roll_deg = finite(c.f32("OffsetRoll"), "OffsetRoll", 360);
  return m;
}

// `geographic`: the file's navigation is latitude and longitude (NavUnits 3), not metres.
Position position(FieldCursor& c, bool geographic) {
  Position p;
  p.time = date_time(c, 1e-4, true);  // the fraction in tenths of a millisecond
  p.latitude_deg = finite(c.f64("RawYcoordinate"), "RawYcoordinate", geographic ? 90 : 1e8);
  p.longitude_deg = finite(c.f64("RawXcoordinate"), "RawXcoordinate", geographic ? 180 : 1e8);
  return p;
}

Attitude attitude(FieldCursor& c) {
  c.skip(8, "reserved");
  const std::uint32_t epoch_us = c.u32("EpochMicroseconds"), epoch_s = c.u32("SourceEpoch");
  if (epoch_us >= 1'000'000u) throw BadField{"EpochMicroseconds", std::to_string(epoch_us) + " is a second or more"};
  Attitude a;
  a.pitch_deg = finite(c.f32("pitch"), "pitch", 180);
  a.roll_deg = finite(c.f32("roll"), "roll", 180);
  a.heave_m = finite(c.f32("heave"), "heave", 100);
  c.skip(4 + 4, "yaw, time tag");
  a.heading_deg = finite(c.f32("heading"), "heading", 720);
  // Writers that fill the epoch leave the date empty and the other way round.
  if (epoch_s != 0) {
    a.time = epoch_s + epoch_us * 1e-6;
  } else {
    a.time = date_time(c, 1e-3, true);
  }
  return a;
}

// The XTF ping header's navigation fields (offsets from the Triton layout, after the packet header).
PingHeaderNavigation ping_header_navigation(FieldCursor& c) {
  // Not checked here: a logger may leave them empty when it writes position and attitude packets.
  PingHeaderNavigation n;
  c.skip(146, "ping header up to SensorYcoordinate");
  n.latitude_deg = c.f64("SensorYcoordinate");
  n.longitude_deg = c.f64("SensorXcoordinate");
  c.skip(178 - 162 + 12, "sonar status, cable, layback, tension, sensor depth and altitudes");
  n.pitch_deg = c.f32("SensorPitch");
  n.roll_deg = c.f32("SensorRoll");
  n.heading_deg = c.f32("SensorHeading");
  n.heave_m = c.f32("Heave");
  c.skip(12, "Yaw, AttitudeTimeTag, DOT");
  n.fix_ms = c.u32("NavFixMilliseconds");
  c.skip(kPingHeaderBytes - 222, "rest of the ping header");
  return n;
}

struct Sections {
  std::optional<std::size_t> h0, r0, a0, a2, q0;
};

// The R2Sonic "BTH0" packet inside an XTF bathymetry packet (big-endian).
BathyPing r2sonic_ping(std::string_view bytes, std::size_t at) {
  FieldCursor head(bytes, at, bytes.size(), ByteOrder::kBig);
  if (head.u32("BTH0 packet name") != kBth0) throw BadField{"BTH0 packet name", "is not \"BTH0\""};
  const std::uint32_t size = head.u32("BTH0 packet size");
  if (size < 12 || size > bytes.size() - at) {
    throw BadField{"BTH0 packet size", std::to_string(size) + " bytes do not fit the " + std::to_string(bytes.size() - at) + " left"};
  }
  head.skip(4, "BTH0 data stream id");
  const std::size_t end = at + size;
  Sections s;
  for (std::size_t k = head.position(); k < end;) {
    FieldCursor c(bytes, k, end, ByteOrder::kBig);
    const std::uint16_t name = c.u16("section name"), section_size = c.u16("section size");
    if (section_size < 4 || section_size > end - k) {
      throw BadField{"section size", std::to_string(section_size) + " bytes do not fit the " + std::to_string(end - k) + " left"};
    }
    if (name == section('H', '0')) s.h0 = k;
    else if (name == section('R', '0')) s.r0 = k;
    else if (name == section('A', '0')) s.a0 = k;
    else if (name == section('A', '2')) s.a2 = k;
    else if (name == section('Q', '0')) s.q0 = k;
    k += section_size;
  }
  if (!s.h0) throw BadField{"H0", "the ping has no H0 section"};
  if (!s.r0) throw BadField{"R0", "the ping has no R0 section (ranges)"};
  if (!s.a0 && !s.a2) throw BadField{"A0", "the ping has neither an A0 nor an A2 section (angles)"};
  const auto cursor = [&](std::size_t k) {
    FieldCursor c(bytes, k, k + FieldCursor(bytes, k + 2, end, ByteOrder::kBig).u16("section size"), ByteOrder::kBig);
    c.skip(4, "section header");
    return c;
  };

  BathyPing p;
  FieldCursor h0 = cursor(*s.h0);
  p.model = h0.text(12, "H0 model number");
  h0.skip(12, "H0 serial number");
  const std::uint32_t seconds = h0.u32("H0 time seconds"), nanoseconds = h0.u32("H0 time nanoseconds");
  if (nanoseconds >= 1'000'000'000u) throw BadField{"H0 time nanoseconds", std::to_string(nanoseconds) + " is a second or more"};
  p.time = seconds + nanoseconds * 1e-9;
  p.ping_number = h0.u32("H0 ping number");
  h0.skip(4, "H0 ping period");
  p.sound_speed_m_s = h0.f32("H0 sound speed");
  if (!(p.sound_speed_m_s > 1300 && p.sound_speed_m_s < 1800)) {
    throw BadField{"H0 sound speed", std::to_string(p.sound_speed_m_s) + " m/s is not the speed of sound in water"};
  }
  h0.skip(114 - 48, "H0 settings");
  const std::uint16_t n = h0.u16("H0 points");
  p.beams.resize(n);

  FieldCursor r0 = cursor(*s.r0);
  const float range_scale = r0.f32("R0 scaling factor");
  // The longest two-way time of any multibeam is well under 10 s (7,500 m at 1,500 m/s).
  if (!(range_scale > 0 && range_scale * 65535 <= 10)) {
    throw BadField{"R0 scaling factor", std::to_string(range_scale) + " s is not a range scale"};
  }
  for (BathyBeam& b : p.beams) b.two_way_time_s = r0.u16("R0 range") * range_scale;

  if (s.a2) {
    FieldCursor a2 = cursor(*s.a2);
    const float first = a2.f32("A2 first angle"), scale = a2.f32("A2 scaling factor");
    if (!std::isfinite(first)) throw BadField{"A2 first angle", "is not a number"};
    if (!std::isfinite(scale)) throw BadField{"A2 scaling factor", "is not a number"};
    a2.skip(24, "A2 reserved");
    std::uint32_t sum = 0;
    for (BathyBeam& b : p.beams) {
      sum += a2.u16("A2 angle step");
      b.angle_rad = static_cast<float>(first + static_cast<double>(sum) * scale);
    }
  } else {
    FieldCursor a0 = cursor(*s.a0);
    const float first = a0.f32("A0 first angle"), last = a0.f32("A0 last angle");
    if (!std::isfinite(first) || !std::isfinite(last)) throw BadField{"A0 first angle", "is not a number"};
    for (std::size_t i = 0; i < n; ++i) {
      p.beams[i].angle_rad = n > 1 ? static_cast<float>(first + (last - first) * static_cast<double>(i) / (n - 1)) : first;
    }
  }
  for (const BathyBeam& b : p.beams) {
    if (std::abs(b.angle_rad) > 1.6f) throw BadField{s.a2 ? "A2 angle step" : "A0 last angle", std::to_string(b.angle_rad) + " rad is beyond the horizontal"};
  }

  if (s.q0) {
    FieldCursor q0 = cursor(*s.q0);
    std::uint32_t word = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (i % 8 == 0) word = q0.u32("Q0 quality");
      p.beams[i].quality = static_cast<std::uint8_t>((word >> (28 - 4 * (i % 8))) & 0xF);
    }
  } else {
    for (BathyBeam& b : p.beams) b.quality = 0xF;  // no flags: every beam with a range counts
  }
  return p;
}

}  // namespace

bool PingHeaderNavigation::position_usable() const {
  return std::isfinite(latitude_deg) && std::isfinite(longitude_deg) && std::abs(latitude_deg) <= 90 &&
         std::abs(longitude_deg) <= 180 && (latitude_deg != 0 || longitude_deg != 0);
}

bool PingHeaderNavigation::attitude_usable() const {
  const auto within = [](double v, double limit) { return std::isfinite(v) && std::abs(v) <= limit; };
  const bool empty = roll_deg == 0 && pitch_deg == 0 && heave_m == 0 && heading_deg == 0;
  return !empty && within(roll_deg, 90) && within(pitch_deg, 90) && within(heave_m, 100) && within(heading_deg, 720);
}

bool BathyBeam::valid() const {
  const bool tests_passed = (quality & 0x3) == 0x3, detected = (quality & 0xC) != 0;
  return tests_passed && detected && two_way_time_s > 0 && std::isfinite(two_way_time_s);
}

XtfError::XtfError(const std::string& file, std::uint64_t offset, const std::string& field, const std::string& what)
    : std::runtime_error(file + ":" + std::to_string(offset) + ": " + field + ": " + what) {}

Reader::Reader(ByteSource& source, std::string file) : source_(source), file_(std::move(file)) {
  bytes_.resize(kFileHeaderBytes);
  const std::size_t got = read_fully(source_, bytes_.data(), kFileHeaderBytes);
  if (got < kFileHeaderBytes) {
    throw XtfError(file_, 0, "file header", "the file ends after " + std::to_string(got) + " of its 1024 bytes");
  }
  try {
    FieldCursor c(bytes_, 0, kFileHeaderBytes, ByteOrder::kLittle);
    if (const std::uint8_t format = c.u8("FileFormat"); format != kFileFormat) {
      throw BadField{"FileFormat", std::to_string(format) + " is not 123 (not an XTF file?)"};
    }
    c.skip(1, "SystemType");
    header_.recording_program = c.text(8, "RecordingProgramName");
    c.skip(8, "RecordingProgramVersion");
    header_.sonar_name = c.text(16, "SonarName");
    header_.sonar_type = c.u16("SonarType");
    c.skip(128, "NoteString, ThisFileName");
    header_.navigation_units = c.u16("NavUnits");
    const int sonar = c.u16("NumberOfSonarChannels");
    header_.bathymetry_channels = c.u16("NumberOfBathymetryChannels");
    const int snippet = c.u8("NumberOfSnippetChannels");
    c.skip(1, "NumberOfForwardLookArrays");
    const int echo = c.u16("NumberOfEchoStrengthChannels");
    const int interferometry = c.u8("NumberOfInterferometryChannels");
    header_.channels = sonar + header_.bathymetry_channels + snippet + echo + interferometry;
    c.skip(3, "reserved");
    header_.reference_point_height_m = finite(c.f32("ReferencePointHeight"), "ReferencePointHeight", 1000);
  } catch (const BadField& bad) {
    throw XtfError(file_, 0, "file header " + bad.field, bad.what);
  }
  // Channel descriptions: six in the header, the rest in 1024-byte blocks after it.
  for (int i = 0; i < header_.channels; ++i) {
    std::size_t at = 256 + (i % 6) * kChannelBytes;
    if (i >= 6) {
      const int k = i - 6;
      if (k % 8 == 0) {
        offset_ += kFileHeaderBytes;
        if (read_fully(source_, bytes_.data(), kFileHeaderBytes) < kFileHeaderBytes) {
          throw XtfError(file_, offset_, "channel descriptions",
                         "the file ends inside the block of channel " + std::to_string(i + 1) + " of " + std::to_string(header_.channels));
        }
      }
      at = (k % 8) * kChannelBytes;
    }
    try {
      FieldCursor c(bytes_, at, at + kChannelBytes, ByteOrder::kLittle);
      const int type = c.u8("TypeOfChannel");
      c.skip(27, "channel name and layout");
      if (type == kBathymetryChannel && !header_.bathymetry) header_.bathymetry = mounting(c);
    } catch (const BadField& bad) {
      throw XtfError(file_, offset_ + at, "channel " + std::to_string(i + 1) + " " + bad.field, bad.what);
    }
  }
  offset_ += kFileHeaderBytes;
}

std::optional<Packet> Reader::next() {
  const std::uint64_t at = offset_;
  packet_offset_ = at;
  char head[kPacketHeaderBytes];
  const std::size_t got = read_fully(source_, head, kPacketHeaderBytes);
  if (got == 0) return std::nullopt;
  if (got < kPacketHeaderBytes) throw XtfError(file_, at, "packet header", "the file ends inside it");
  FieldCursor h(std::string_view(head, kPacketHeaderBytes), 0, kPacketHeaderBytes, ByteOrder::kLittle);
  if (const std::uint16_t magic = h.u16("magic number"); magic != kPacketMagic) {
    throw XtfError(file_, at, "packet magic number", format("0x%04X is not 0xFACE", magic));
  }
  const std::uint8_t type = h.u8("header type");
  h.skip(7, "sub-channel, channels to follow, reserved");
  const std::uint32_t length = h.u32("NumBytesThisRecord");
  if (length < kPacketHeaderBytes) {
    throw XtfError(file_, at, "NumBytesThisRecord", std::to_string(length) + " bytes is shorter than a packet header");
  }
  if (length > kMaxPacketBytes) {
    throw XtfError(file_, at, "NumBytesThisRecord",
                   std::to_string(length) + " bytes is over the " + std::to_string(kMaxPacketBytes) + "-byte limit");
  }
  const std::size_t body = length - kPacketHeaderBytes;
  if (const std::size_t got = read_record(source_, body, bytes_); got < body) {
    throw XtfError(file_, at, "NumBytesThisRecord",
                   std::to_string(length) + " bytes run past the end of the file (" + std::to_string(kPacketHeaderBytes + got) + " left)");
  }
  offset_ += length;
  ++packets_;
  try {
    FieldCursor c(bytes_, 0, bytes_.size(), ByteOrder::kLittle);
    switch (type) {
      case kPosition: return position(c, header_.navigation_units == 3);
      case kAttitude: return attitude(c);
      case kR2SonicBathymetry: {
        const PingHeaderNavigation header = ping_header_navigation(c);
        BathyPing ping = r2sonic_ping(bytes_, kPingHeaderBytes);
        ping.header = header;
        return ping;
      }
      default: return Skipped{type};
    }
  } catch (const BadField& bad) {
    const char* kind = type == kPosition ? "position packet " : type == kAttitude ? "attitude packet " : "R2Sonic bathymetry packet ";
    throw XtfError(file_, at, kind + bad.field, bad.what);
  }
}

}  // namespace bathyslam::xtf
