#pragma once
// XTF files (Triton "eXtended Triton Format", rev. 40+), packet by packet: the file header with
// the bathymetry channel's mounting, and the packets a multibeam survey logged by QINSy from an
// R2Sonic sonar holds, decoded into engineering units; the others skipped by their length.
//
// Framing: a 1024-byte file header (format byte 123, six 128-byte channel descriptions; more
// channels follow in 1024-byte blocks), then packets, each a 14-byte little-endian header (magic
// 0xFACE, type, sub-channel, channels to follow, the packet's byte count including the header) and
// its body. The R2Sonic bathymetry packet (type 65) carries, after the 256-byte XTF ping header,
// R2Sonic's own big-endian "BTH0" packet: sections H0 (ping), R0 (two-way times), A0 or A2
// (beam angles), Q0 (quality flags) and others skipped.
//
// Damaged input never crashes or hangs the reader: every problem is an XtfError that reads
// `file:offset: field: message`, the offset that of the packet's header.
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "core/io/byte_source.h"

namespace bathyslam::xtf {

enum PacketType : std::uint8_t {
  kAttitude = 3,
  kR2SonicBathymetry = 65,  // XTF_HEADER_QINSY_R2SONIC_BATHY
  kPosition = 107,          // XTF_HEADER_POSITION (raw position of the navigation system)
};

// Where the bathymetry channel's sonar sits on the vessel (its channel description): metres from
// the reference point, degrees of rotation (x starboard, y forward, z down; yaw to starboard,
// pitch bow up, roll starboard down).
struct Mounting {
  double starboard_m = 0, forward_m = 0, down_m = 0;
  double yaw_deg = 0, pitch_deg = 0, roll_deg = 0;
};

struct FileHeader {
  std::string recording_program, sonar_name;
  int sonar_type = 0;
  int navigation_units = 0;  // 3: latitude and longitude in degrees; 0: projected metres
  int bathymetry_channels = 0, channels = 0;
  double reference_point_height_m = 0;  // above the water line
  std::optional<Mounting> bathymetry;   // of the first bathymetry channel
};

// A position fix of the navigation system (packet 107).
struct Position {
  double time = 0;  // seconds since the epoch
  double latitude_deg = 0, longitude_deg = 0;  // or y / x in metres (navigation units 0)
};

// A motion-sensor sample (packet 3).
struct Attitude {
  double time = 0;
  double roll_deg = 0, pitch_deg = 0, heave_m = 0, heading_deg = 0;  // heave positive up
};

// One beam of an R2Sonic ping: its two-way travel time and its angle across the array.
struct BathyBeam {
  float two_way_time_s = 0;
  float angle_rad = 0;      // from the array's centreline, positive to starboard
  std::uint8_t quality = 0; // Q0's four flags: bit 0 brightness, 1 colinearity, 2 magnitude, 3 phase
  bool valid() const;
};

// What the logger wrote into the XTF ping header of a bathymetry packet: its latest navigation,
// used when a file has no position or attitude packets of its own.
struct PingHeaderNavigation {
  double latitude_deg = 0, longitude_deg = 0;  // SensorY/Xcoordinate
  std::uint32_t fix_ms = 0;  // NavFixMilliseconds: the fix's time of day (ms since midnight), 0: not given
  double roll_deg = 0, pitch_deg = 0, heave_m = 0, heading_deg = 0;
  bool position_usable() const;  // finite and on the Earth
  bool attitude_usable() const;  // finite, within a turn, and not all zero (a logger leaving it empty)
};

// An R2Sonic ping (packet 65).
struct BathyPing {
  double time = 0;
  std::uint32_t ping_number = 0;
  std::string model;           // e.g. "2026"
  double sound_speed_m_s = 0;  // at the array, as the sonar used it
  std::vector<BathyBeam> beams;
  PingHeaderNavigation header;
};

struct Skipped {
  std::uint8_t type = 0;
};

using Packet = std::variant<BathyPing, Position, Attitude, Skipped>;

class XtfError : public std::runtime_error {
 public:
  XtfError(const std::string& file, std::uint64_t offset, const std::string& field, const std::string& what);
};

// Packets larger than this are refused before anything is allocated.
inline constexpr std::uint32_t kMaxPacketBytes = 64u << 20;

class Reader {
 public:
  // Reads the file header. Throws XtfError.
  Reader(ByteSource& source, std::string file);
  const FileHeader& header() const { return header_; }
  // The next packet, or nothing at the end of the file. Throws XtfError.
  std::optional<Packet> next();
  std::uint64_t bytes_read() const { return offset_; }
  std::uint64_t packet_offset() const { return packet_offset_; }  // of the last packet's header
  std::uint64_t packets_read() const { return packets_; }

 private:
  ByteSource& source_;
  std::string file_;
  FileHeader header_;
  std::uint64_t offset_ = 0, packet_offset_ = 0;
  std::uint64_t packets_ = 0;
  std::string bytes_;
};

}  // namespace bathyslam::xtf
