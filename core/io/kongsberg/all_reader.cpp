#include <cmath>
#include <cstring>

#include "core/io/kongsberg/all_datagrams.h"

#include "core/io/binary_fields.h"

namespace bathyslam::kongsberg {
namespace {

// The body of a datagram: from after its header to before ETX and the checksum.
FieldCursor body_cursor(const std::string& bytes) { return FieldCursor(bytes, 2, bytes.size() - 3, ByteOrder::kLittle); }

double epoch_seconds(std::uint32_t date, std::uint32_t ms) {
  const int year = static_cast<int>(date / 10000), month = static_cast<int>(date / 100 % 100),
            day = static_cast<int>(date % 100);
  if (year < 1980 || year > 2200 || month < 1 || month > 12 || day < 1 || day > 31) {
    throw BadField{"date", std::to_string(date) + " is not a YYYYMMDD date"};
  }
  if (ms >= 86'400'000u) throw BadField{"time", std::to_string(ms) + " ms is past midnight"};
  return static_cast<double>(days_from_civil(year, month, day)) * 86400.0 + ms / 1000.0;
}

DepthPing xyz88(FieldCursor& c, double time, std::uint16_t counter, std::uint16_t serial) {
  DepthPing p;
  p.time = time;
  p.counter = counter;
  p.serial = serial;
  p.heading_deg = c.u16("heading") / 100.0;
  p.sound_speed_m_s = c.u16("sound speed") / 10.0;
  p.transducer_depth_m = c.f32("transmit transducer depth");
  if (!std::isfinite(p.transducer_depth_m) || std::abs(p.transducer_depth_m) > 12000) {
    throw BadField{"transmit transducer depth", std::to_string(p.transducer_depth_m) + " m is not a depth"};
  }
  const std::uint16_t beams = c.u16("number of beams");
  c.skip(2 + 4 + 1 + 3, "valid detections, sampling frequency, scanning info");
  p.beams.resize(beams);
  for (DepthBeam& b : p.beams) {
    b.depth_m = c.f32("beam depth");
    b.across_m = c.f32("beam across-track distance");
    b.along_m = c.f32("beam along-track distance");
    c.skip(2 + 1 + 1, "detection window, quality, incidence adjustment");
    b.detection = c.u8("detection information");
    c.skip(1 + 2, "cleaning, reflectivity");
  }
  return p;
}

Position position(FieldCursor& c, double time) {
  Position p;
  p.time = time;
  p.latitude_deg = c.i32("latitude") / 2.0e7;
  p.longitude_deg = c.i32("longitude") / 1.0e7;
  if (std::abs(p.latitude_deg) > 90) throw BadField{"latitude", std::to_string(p.latitude_deg) + " deg is off the Earth"};
  if (std::abs(p.longitude_deg) > 180) throw BadField{"longitude", std::to_string(p.longitude_deg) + " deg is off the Earth"};
  c.skip(2 + 2 + 2, "fix quality, speed, course");
  p.heading_deg = c.u16("heading") / 100.0;
  const std::uint8_t descriptor = c.u8("position system descriptor");
  p.system = descriptor & 0x03;
  p.active = (descriptor & 0x80) != 0;
  return p;
}

Attitude attitude(FieldCursor& c, double time) {
  Attitude a;
  const std::uint16_t n = c.u16("number of entries");
  for (std::uint16_t i = 0; i < n; ++i) {
    a.time.push_back(time + c.u16("attitude sample time") / 1000.0);
    c.skip(2, "sensor status");
    a.roll_deg.push_back(c.i16("roll") / 100.0);
    a.pitch_deg.push_back(c.i16("pitch") / 100.0);
    a.heave_m.push_back(c.i16("heave") / 100.0);
    a.heading_deg.push_back(c.u16("heading") / 100.0);
  }
  return a;
}

SoundSpeedProfile sound_speed_profile(FieldCursor& c) {
  SoundSpeedProfile p;
  p.date = c.u32("profile date");
  p.time_ms = c.u32("profile time");
  const std::uint16_t entries = c.u16("number of entries");
  const std::uint16_t resolution_cm = c.u16("depth resolution");
  for (std::uint16_t i = 0; i < entries; ++i) {
    p.depth_m.push_back(c.u32("profile depth") * resolution_cm / 100.0);
    p.sound_speed_m_s.push_back(c.u32("sound speed") / 10.0);
  }
  return p;
}

Installation installation(FieldCursor& c) {
  c.skip(2 + 2, "line number, second head serial");
  return {c.text(c.left(), "installation text")};  // NUL-terminated, then padding
}

}  // namespace

bool DepthBeam::valid() const {
  return (detection & 0x80) == 0 && std::isfinite(depth_m) && std::isfinite(across_m) && std::isfinite(along_m);
}

AllError::AllError(const std::string& file, std::uint64_t offset, const std::string& field, const std::string& what)
    : std::runtime_error(file + ":" + std::to_string(offset) + ": " + field + ": " + what) {}

Reader::Reader(ByteSource& source, std::string file) : source_(source), file_(std::move(file)) {}

std::optional<Datagram> Reader::next() {
  const std::uint64_t at = offset_;
  char length_bytes[4];
  const std::size_t got = read_fully(source_, length_bytes, 4);
  if (got == 0) return std::nullopt;
  if (got < 4) throw AllError(file_, at, "datagram length", "the file ends inside it");
  std::uint32_t length = 0;
  for (int i = 3; i >= 0; --i) length = (length << 8) | static_cast<unsigned char>(length_bytes[i]);
  if (length < 19) throw AllError(file_, at, "datagram length", std::to_string(length) + " bytes is shorter than a datagram's frame");
  if (length > kMaxDatagramBytes) {
    throw AllError(file_, at, "datagram length", std::to_string(length) + " bytes is over the " +
                                                   std::to_string(kMaxDatagramBytes) + "-byte limit");
  }
  if (const std::size_t got = read_record(source_, length, bytes_); got < length) {
    throw AllError(file_, at, "datagram length",
                   std::to_string(length) + " bytes run past the end of the file (" + std::to_string(got) + " left)");
  }
  offset_ += 4 + length;
  ++datagrams_;
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(bytes_[i]); };
  if (byte(0) != 0x02) throw AllError(file_, at, "STX", "the datagram does not start with 0x02 (not an EM .all file?)");
  if (byte(length - 3) != 0x03) throw AllError(file_, at, "ETX", "the datagram does not end with 0x03 where its length says");
  std::uint16_t sum = 0;
  for (std::size_t i = 1; i < length - 3; ++i) sum = static_cast<std::uint16_t>(sum + byte(i));
  const std::uint16_t stored = static_cast<std::uint16_t>(byte(length - 2) | (byte(length - 1) << 8));
  if (sum != stored) {
    throw AllError(file_, at, "checksum", "the bytes sum to " + std::to_string(sum) + ", the datagram says " + std::to_string(stored));
  }
  const std::uint8_t type = byte(1);
  try {
    FieldCursor c = body_cursor(bytes_);
    model_ = c.u16("EM model");
    const std::uint32_t date = c.u32("date"), ms = c.u32("time");
    const std::uint16_t counter = c.u16("counter"), serial = c.u16("serial number");
    switch (type) {
      case kXyz88: return xyz88(c, epoch_seconds(date, ms), counter, serial);
      case kPosition: return position(c, epoch_seconds(date, ms));
      case kAttitude: return attitude(c, epoch_seconds(date, ms));
      case kInstallationStart: return installation(c);
      case kSoundSpeedProfile: return sound_speed_profile(c);
      default: return Skipped{type};
    }
  } catch (const BadField& bad) {
    const std::string kind = type >= 0x20 && type < 0x7f ? std::string("'") + static_cast<char>(type) + "' " : "";
    throw AllError(file_, at, kind + "datagram " + bad.field, bad.what);
  }
}

}  // namespace bathyslam::kongsberg
