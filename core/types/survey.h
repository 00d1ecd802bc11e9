#pragma once
// The survey as it comes off the vehicle: navigation, pings and their beams.
//
// Frames and units (docs/design.md, "Conventions"):
//  - navigation: projected CRS easting/northing in metres, depth in metres positive down,
//    roll/pitch/heading in degrees, heading clockwise from north;
//  - beams: the sonar's ray-traced solution in the vehicle frame (x forward, y starboard,
//    z down), metres;
//  - times: seconds since the Unix epoch, UTC.
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bathyslam {

struct NavSample {
  double time = 0;
  double easting = 0;
  double northing = 0;
  double depth_m = 0;
  double roll_deg = 0;
  double pitch_deg = 0;
  double heading_deg = 0;
};

// One sounding of a ping. Floats keep the 15 M soundings of a survey in ~240 MB and still
// resolve micrometres at sonar ranges.
struct Beam {
  uint32_t index = 0;
  float along = 0;
  float across = 0;
  float down = 0;
};

// A ping owns the beams [first_beam, first_beam + beam_count) of Survey::beams.
struct Ping {
  double time = 0;
  uint32_t first_beam = 0;
  uint32_t beam_count = 0;
};

struct SurveyMetadata {
  std::string name;
  std::string crs;  // "EPSG:<code>", a projected CRS in metres
  nlohmann::json sonar = nlohmann::json::object();
  nlohmann::json vehicle = nlohmann::json::object();
};

struct Survey {
  SurveyMetadata metadata;
  std::vector<NavSample> nav;
  std::vector<Ping> pings;
  std::vector<Beam> beams;
  std::optional<std::vector<NavSample>> reference_nav;

  std::span<const Beam> beams_of(const Ping& ping) const {
    return {beams.data() + ping.first_beam, ping.beam_count};
  }
};

}  // namespace bathyslam
