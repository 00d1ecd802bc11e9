#pragma once
// Kongsberg EM `.all` files, datagram by datagram (Kongsberg "EM datagram formats", the
// little-endian layout every EM 710/122/302/2040 writes): the datagrams a survey needs decoded into
// engineering units, the others skipped by their length.
//
// Framing: a 4-byte length (the bytes that follow), STX (0x02), the type, the EM model, the date
// (YYYYMMDD) and time (ms since midnight, UTC), a counter and the system's serial number, the body,
// ETX (0x03) and a 16-bit sum of the bytes from the type to the one before ETX.
//
// Damaged input never crashes or hangs the reader: every problem is an AllError that reads
// `file:offset: field: message`, the offset that of the datagram's length field.
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "core/io/byte_source.h"

namespace bathyslam::kongsberg {

enum DatagramType : std::uint8_t {
  kAttitude = 'A',
  kInstallationStart = 'I',
  kPosition = 'P',
  kSoundSpeedProfile = 'U',
  kXyz88 = 'X',
};

// A position fix of one positioning system (datagram 'P'), of its reference point.
struct Position {
  double time = 0;  // seconds since the epoch
  double latitude_deg = 0, longitude_deg = 0;
  double heading_deg = 0;
  int system = 0;       // 1-3
  bool active = false;  // the system the sonar used in real time (descriptor bit 7)
};

// Motion-sensor samples (datagram 'A').
struct Attitude {
  std::vector<double> time;  // seconds since the epoch
  std::vector<double> roll_deg, pitch_deg, heave_m, heading_deg;
};

// One beam of an XYZ 88 datagram: relative to the transmit transducer (depth) and the active
// positioning system's reference point (along, across), in a level frame aligned with the heading
// (x forward, y starboard, z down); attitude, heave and ray bending already applied.
struct DepthBeam {
  float depth_m = 0, across_m = 0, along_m = 0;
  std::uint8_t detection = 0;  // bit 7 set: no valid detection
  bool valid() const;
};

// A swath of one sonar head (datagram 'X'); a dual-head or dual-swath ping is several.
struct DepthPing {
  double time = 0;
  std::uint16_t counter = 0, serial = 0;
  double heading_deg = 0;
  double sound_speed_m_s = 0;
  double transducer_depth_m = 0;  // below the water level at the ping, heave included
  std::vector<DepthBeam> beams;
};

// The installation parameters (datagram 'I'): "KEY=value," text as the sonar wrote it.
struct Installation {
  std::string text;
};

// A sound speed profile as the sonar used it (datagram 'U').
struct SoundSpeedProfile {
  std::uint32_t date = 0, time_ms = 0;  // when the profile was taken, as the datagram says
  std::vector<double> depth_m, sound_speed_m_s;
};

struct Skipped {
  std::uint8_t type = 0;
};

using Datagram = std::variant<DepthPing, Position, Attitude, Installation, SoundSpeedProfile, Skipped>;

class AllError : public std::runtime_error {
 public:
  AllError(const std::string& file, std::uint64_t offset, const std::string& field, const std::string& what);
};

// Datagrams larger than this are refused before anything is allocated (a water-column datagram
// of a 1,024-beam head is a few MiB).
inline constexpr std::uint32_t kMaxDatagramBytes = 64u << 20;

class Reader {
 public:
  Reader(ByteSource& source, std::string file);
  // The next datagram, or nothing at the end of the file. Throws AllError.
  std::optional<Datagram> next();
  std::uint64_t bytes_read() const { return offset_; }
  std::uint64_t datagrams_read() const { return datagrams_; }
  std::uint16_t model() const { return model_; }  // of the last datagram, e.g. 2040

 private:
  ByteSource& source_;
  std::string file_;
  std::uint64_t offset_ = 0;
  std::uint64_t datagrams_ = 0;
  std::uint16_t model_ = 0;
  std::string bytes_;
};

}  // namespace bathyslam::kongsberg
