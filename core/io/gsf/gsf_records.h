#pragma once
// The GSF records bathyslam reads and writes (GSF specification 03.11, section 4.3), decoded into
// engineering units: metres, seconds since the Unix epoch, degrees, hundredths already divided out.
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

namespace bathyslam::gsf {

// Record identifiers of registry 0 (Appendix A.1).
enum RecordId : std::uint32_t {
  kHeader = 1,
  kSwathBathymetryPing = 2,
  kSoundVelocityProfile = 3,
  kProcessingParameters = 4,
  kSensorParameters = 5,
  kComment = 6,
  kHistory = 7,
  kNavigationError = 8,
  kSwathBathySummary = 9,
  kSingleBeamSounding = 10,
  kHvNavigationError = 11,
  kAttitude = 12,
};
inline constexpr std::uint32_t kLastRecordId = kAttitude;

// Ping subrecord identifiers (Appendix A.2) that bathyslam decodes; the others are skipped.
enum SubrecordId : std::uint8_t {
  kDepthArray = 1,
  kAcrossTrackArray = 2,
  kAlongTrackArray = 3,
  kTravelTimeArray = 4,
  kBeamAngleArray = 5,
  kBeamFlagsArray = 16,
  kScaleFactors = 100,
};

// Ping header sizes: 56 bytes from GSF 3.01 on (height, separation, GPS tide corrector, spare).
inline constexpr std::size_t kPingHeaderBytes = 56;
inline constexpr std::size_t kPingHeaderBytesBefore301 = 42;

struct Header {
  std::string version;  // "GSF-v03.07"
  int major = 0, minor = 0;
};

// One swath bathymetry ping. Beam arrays hold num_beams values (port to starboard) or are empty
// when the ping has no such subrecord. Depths, across- and along-track are relative to the
// reference point whose position the header gives, in a level frame aligned with the heading:
// x along-track forward, y across-track starboard, z depth down from the water surface (the depth
// corrector, i.e. the vehicle's depth, and the tide corrector already added).
struct Ping {
  double time = 0;
  double longitude_deg = 0, latitude_deg = 0;
  int num_beams = 0;
  int center_beam = 0;
  std::uint16_t flags = 0;
  double tide_corrector_m = 0;
  double depth_corrector_m = 0;  // dynamic draft; the vehicle's depth for a submersible
  double heading_deg = 0, pitch_deg = 0, roll_deg = 0;
  double heave_m = 0;
  double course_deg = 0;
  double speed_knots = 0;
  std::vector<double> depth_m, across_m, along_m;
  std::vector<double> travel_time_s, beam_angle_deg;
  std::vector<std::uint8_t> beam_flags;

  // Bit 0 of the ping flags: the whole ping is not to be used (section 4.3.4.1).
  bool ignored() const { return (flags & 1u) != 0; }
  // Bit 0 of a beam's flags: the beam is not to be used (section 4.3.4.15).
  bool beam_rejected(std::size_t beam) const { return !beam_flags.empty() && (beam_flags[beam] & 1u) != 0; }
};

// A run of motion-sensor measurements (section 4.3.14).
struct Attitude {
  std::vector<double> time;  // seconds since the epoch
  std::vector<double> pitch_deg, roll_deg, heave_m, heading_deg;
};

struct SoundVelocityProfile {
  double observed_time = 0, applied_time = 0;
  double longitude_deg = 0, latitude_deg = 0;
  std::vector<double> depth_m, sound_velocity_m_s;
};

struct ProcessingParameters {
  double time = 0;
  std::vector<std::string> parameters;  // "KEYWORD=VALUE"
};

struct Comment {
  double time = 0;
  std::string text;
};

// A record bathyslam does not decode (sensor parameters, history, summary, navigation error,
// single-beam, or a private registry's): skipped by its size.
struct Skipped {
  std::uint32_t registry = 0;
  std::uint32_t type = 0;
};

using Record = std::variant<Header, Ping, Attitude, SoundVelocityProfile, ProcessingParameters, Comment, Skipped>;

}  // namespace bathyslam::gsf
