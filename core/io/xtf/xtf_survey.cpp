#include "core/io/xtf/xtf_survey.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>

#include "core/io/file_extension.h"
#include "core/io/sonar_tracks.h"
#include "core/io/xtf/xtf_packets.h"
#include "core/types/format.h"
#include "core/types/pose.h"

namespace bathyslam::xtf {
namespace {

constexpr int kLatitudeLongitude = 3;  // NavUnits
constexpr double kDegToRad = M_PI / 180.0;
// Motion sensors report at 10 Hz or more: attitude a second or more away is a dropout, and a ping
// there has no roll or heading to be georeferenced with.
constexpr double kMaxAttitudeGap_s = 1.0;

std::string utc(double seconds) { return format_utc(seconds, "%Y-%m-%dT%H:%M:%SZ"); }

// How a file's beams become positions in the vessel frame.
struct Geometry {
  Eigen::Vector3d lever;     // the array from the reference point: forward, starboard, down
  Eigen::Matrix3d rotation;  // array to vessel
  double reference_height_m = 0;
};

Geometry geometry_of(const Reader& reader, const std::filesystem::path& path) {
  const FileHeader& h = reader.header();
  if (h.navigation_units != kLatitudeLongitude) {
    throw std::runtime_error(path.string() + ": file header NavUnits: " + std::to_string(h.navigation_units) +
                             " (projected coordinates) is not read; bathyslam reads latitude and longitude (3)");
  }
  if (h.bathymetry_channels > 1) {
    throw std::runtime_error(path.string() + ": file header NumberOfBathymetryChannels: " + std::to_string(h.bathymetry_channels) +
                             " (several sonar heads) is not read; bathyslam reads one head's XTF");
  }
  if (!h.bathymetry) {
    throw std::runtime_error(path.string() + ": file header: no bathymetry channel is described (the sonar's mounting)");
  }
  const Mounting& m = *h.bathymetry;
  const Eigen::Matrix3d rotation = (Eigen::AngleAxisd(m.yaw_deg * kDegToRad, Eigen::Vector3d::UnitZ()) *
                                    Eigen::AngleAxisd(m.pitch_deg * kDegToRad, Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(m.roll_deg * kDegToRad, Eigen::Vector3d::UnitX()))
                                       .toRotationMatrix();
  return {Eigen::Vector3d(m.forward_m, m.starboard_m, m.down_m), rotation, h.reference_point_height_m};
}

double slant_range_m(const BathyPing& p, const BathyBeam& b) { return p.sound_speed_m_s * b.two_way_time_s / 2; }

// The ping's valid soundings in the vessel frame, appended to `beams`: straight rays at the
// array's sound speed, across the array (positive angles to starboard), mounted as the file says.
void append_soundings(const BathyPing& p, const Geometry& g, std::vector<Beam>& beams) {
  for (std::size_t i = 0; i < p.beams.size(); ++i) {
    const BathyBeam& b = p.beams[i];
    if (!b.valid()) continue;
    const double r = slant_range_m(p, b);
    const Eigen::Vector3d v = g.lever + g.rotation * Eigen::Vector3d(0, r * std::sin(b.angle_rad), r * std::cos(b.angle_rad));
    beams.push_back({static_cast<std::uint32_t>(i), static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())});
  }
}

std::uint32_t valid_beams(const BathyPing& p) {
  return static_cast<std::uint32_t>(std::count_if(p.beams.begin(), p.beams.end(), [](const BathyBeam& b) { return b.valid(); }));
}

// A ping between the packet and the survey.
struct PingRecord {
  double time = 0;
  std::size_t file = 0;
  std::uint32_t soundings = 0;
  PingHeaderNavigation header;
  std::optional<BathyPing> kept;  // with its beams, when soundings are kept
};

void widen(bool first, double& lo, double& hi, double v) {
  lo = first ? v : std::min(lo, v);
  hi = first ? v : std::max(hi, v);
}

void add_fix(FileSummary& s, double latitude, double longitude) {
  widen(s.positions == 0, s.latitude_min, s.latitude_max, latitude);
  widen(s.positions == 0, s.longitude_min, s.longitude_max, longitude);
  ++s.positions;
}

// When the fix a ping header carries was taken: its time of day (NavFixMilliseconds) on the ping's
// day, the nearer midnight's side; without it, the ping's own time.
double header_fix_time(const PingRecord& r) {
  if (r.header.fix_ms == 0 || r.header.fix_ms >= 86'400'000u) return r.time;
  double t = std::floor(r.time / 86400) * 86400 + r.header.fix_ms / 1000.0;
  if (t - r.time > 43200) t -= 86400;
  if (r.time - t > 43200) t += 86400;
  return t;
}

class SummaryBuilder {
 public:
  SummaryBuilder(std::string file, const FileHeader& header) {
    s_.file = std::move(file);
    s_.recording_program = header.recording_program;
    s_.sonar = header.sonar_name;
  }
  void add(const Packet& p, std::uint8_t type) {
    ++s_.packets_by_type[type];
    if (const auto* ping = std::get_if<BathyPing>(&p)) add_ping(*ping);
    else if (const auto* fix = std::get_if<Position>(&p)) add_fix(s_, fix->latitude_deg, fix->longitude_deg);
    else if (std::holds_alternative<Attitude>(p)) ++s_.attitude_samples;
  }
  FileSummary finish(std::uint64_t bytes, std::uint64_t packets) {
    s_.bytes = bytes;
    s_.packets = packets;
    return s_;
  }

 private:
  void add_ping(const BathyPing& p) {
    widen(s_.pings == 0, s_.time_begin, s_.time_end, p.time);
    if (s_.sonar.empty() && !p.model.empty()) s_.sonar = "R2Sonic " + p.model;
    ++s_.pings;
    s_.beams += p.beams.size();
    for (const BathyBeam& b : p.beams) {
      if (!b.valid()) {
        ++s_.rejected_beams;
        continue;
      }
      widen(s_.soundings == 0, s_.range_min_m, s_.range_max_m, slant_range_m(p, b));
      ++s_.soundings;
    }
  }
  FileSummary s_;
};

std::uint8_t type_of(const Packet& p) {
  if (std::holds_alternative<BathyPing>(p)) return kR2SonicBathymetry;
  if (std::holds_alternative<Position>(p)) return kPosition;
  if (std::holds_alternative<Attitude>(p)) return kAttitude;
  return std::get<Skipped>(p).type;
}

std::string where(const std::filesystem::path& path, const Reader& reader) {
  return path.string() + ":" + std::to_string(reader.packet_offset());
}

// Pings come in time order within and across files (one sonar head).
void check_order(double time, double& last, const std::string& at) {
  if (time < last) {
    throw std::runtime_error(at + ": ping at " + utc(time) + " comes after a later one (" + utc(last) +
                             "); give the files in time order");
  }
  last = time;
}

std::string packet_name(int type) {
  if (type == kR2SonicBathymetry) return "R2Sonic bathymetry";
  if (type == kPosition) return "position";
  if (type == kAttitude) return "attitude";
  return "other";
}

}  // namespace

nlohmann::json to_json(const FileSummary& s) {
  nlohmann::json by_type = nlohmann::json::object();
  for (const auto& [type, n] : s.packets_by_type) by_type[std::to_string(type)] = n;
  return {{"file", s.file},
          {"format", "XTF"},
          {"recording_program", s.recording_program},
          {"sonar", s.sonar},
          {"bytes", s.bytes},
          {"packets", s.packets},
          {"packets_by_type", by_type},
          {"pings", s.pings},
          {"beams", s.beams},
          {"soundings", s.soundings},
          {"rejected_beams", s.rejected_beams},
          {"pings_outside_navigation", s.pings_outside_navigation},
          {"positions", s.positions},
          {"attitude_samples", s.attitude_samples},
          {"navigation_from_ping_headers", s.navigation_from_ping_headers},
          {"time_begin", utc(s.time_begin)},
          {"time_end", utc(s.time_end)},
          {"latitude_deg", {s.latitude_min, s.latitude_max}},
          {"longitude_deg", {s.longitude_min, s.longitude_max}},
          {"slant_range_m", {s.range_min_m, s.range_max_m}}};
}

std::string to_text(const FileSummary& s) {
  std::string packets;
  for (const auto& [type, n] : s.packets_by_type) {
    packets += format("%s%llu %s (%d)", packets.empty() ? "" : ", ", static_cast<unsigned long long>(n), packet_name(type).c_str(), type);
  }
  return format("%s: XTF from %s, %s, %llu bytes, %llu packets\n", s.file.c_str(), s.recording_program.c_str(),
                s.sonar.c_str(), static_cast<unsigned long long>(s.bytes), static_cast<unsigned long long>(s.packets)) +
         format("  packets     %s\n", packets.c_str()) +
         format("  pings       %llu, %llu outside the position fixes or the attitude\n", static_cast<unsigned long long>(s.pings),
                static_cast<unsigned long long>(s.pings_outside_navigation)) +
         format("  soundings   %llu of %llu beams (%llu rejected)\n", static_cast<unsigned long long>(s.soundings),
                static_cast<unsigned long long>(s.beams), static_cast<unsigned long long>(s.rejected_beams)) +
         format("  time        %s .. %s\n", utc(s.time_begin).c_str(), utc(s.time_end).c_str()) +
         format("  latitude    %.5f .. %.5f\n  longitude   %.5f .. %.5f\n", s.latitude_min, s.latitude_max,
                s.longitude_min, s.longitude_max) +
         format("  ranges      %.1f .. %.1f m slant\n", s.range_min_m, s.range_max_m) +
         format("  navigation  %llu position fixes, %llu attitude samples%s\n", static_cast<unsigned long long>(s.positions),
                static_cast<unsigned long long>(s.attitude_samples),
                s.navigation_from_ping_headers ? " (from the ping headers: the file has no such packets)" : "");
}

SurveyRead read_survey(const std::vector<std::filesystem::path>& files, const ReadOptions& options) {
  if (files.empty()) throw std::runtime_error("no .xtf file given");
  SurveyRead out;
  std::vector<GeodeticFix> fixes;
  AttitudeTrack motion;
  std::vector<Geometry> geometry;
  std::vector<PingRecord> pings;
  double last = -INFINITY;
  for (std::size_t f = 0; f < files.size(); ++f) {
    FileSource source(files[f]);
    Reader reader(source, files[f].string());
    geometry.push_back(geometry_of(reader, files[f]));
    SummaryBuilder summary(files[f].filename().string(), reader.header());
    while (auto packet = reader.next()) {
      summary.add(*packet, type_of(*packet));
      if (auto* p = std::get_if<BathyPing>(&*packet)) {
        check_order(p->time, last, where(files[f], reader));
        PingRecord record{p->time, f, valid_beams(*p), p->header, std::nullopt};
        if (options.keep_soundings) record.kept = std::move(*p);
        pings.push_back(std::move(record));
      } else if (const auto* fix = std::get_if<Position>(&*packet)) {
        // (0, 0): what some loggers write before the receiver has a fix.
        if (fix->latitude_deg != 0 || fix->longitude_deg != 0) fixes.push_back({fix->time, fix->latitude_deg, fix->longitude_deg});
      } else if (const auto* a = std::get_if<Attitude>(&*packet)) {
        motion.add({a->time, a->roll_deg, a->pitch_deg, a->heave_m, a->heading_deg});
      }
    }
    out.files.push_back(summary.finish(reader.bytes_read(), reader.packets_read()));
  }
  // Without position or attitude packets: what the logger wrote into each ping's header.
  // Decided file by file: a file between two that have position packets is not to be navigated by
  // interpolating across it.
  std::vector<char> header_fixes(files.size()), header_motion(files.size());
  for (std::size_t f = 0; f < files.size(); ++f) {
    header_fixes[f] = out.files[f].positions == 0;
    header_motion[f] = out.files[f].attitude_samples == 0;
  }
  double last_header_fix = -INFINITY;
  for (const PingRecord& r : pings) {
    const double fix_time = header_fix_time(r);
    if (header_fixes[r.file] && r.header.position_usable() && fix_time > last_header_fix) {
      fixes.push_back({fix_time, r.header.latitude_deg, r.header.longitude_deg});
      add_fix(out.files[r.file], r.header.latitude_deg, r.header.longitude_deg);
      out.files[r.file].navigation_from_ping_headers = true;
      last_header_fix = fix_time;
    }
    if (header_motion[r.file] && r.header.attitude_usable()) {
      motion.add({r.time, r.header.roll_deg, r.header.pitch_deg, r.header.heave_m, r.header.heading_deg});
      out.files[r.file].navigation_from_ping_headers = true;
    }
  }
  motion.sort();
  const GeodeticTrack track(std::move(fixes));

  Survey& survey = out.survey;
  survey.metadata.name = files.front().stem().string();
  FixProjection projection(options.crs);
  for (PingRecord& r : pings) {
    const auto fix = track.at(r.time);
    if (!fix || motion.gap_at(r.time) > kMaxAttitudeGap_s) {
      ++out.files[r.file].pings_outside_navigation;
      continue;
    }
    if (survey.nav.empty() || r.time > survey.nav.back().time) {
      const auto [easting, northing] = projection.forward(fix->first, fix->second, files[r.file].string() + " at " + utc(r.time));
      const AttitudeSample m = motion.at(r.time);
      const double depth = -geometry[r.file].reference_height_m - m.heave_m;
      survey.nav.push_back({r.time, easting, northing, depth, m.roll_deg, m.pitch_deg, m.heading_deg});
    }
    Ping ping{r.time, static_cast<std::uint32_t>(survey.beams.size()), r.soundings};
    if (r.kept) {
      append_soundings(*r.kept, geometry[r.file], survey.beams);
      ping.beam_count = static_cast<std::uint32_t>(survey.beams.size()) - ping.first_beam;
      r.kept.reset();
    }
    if (ping.beam_count > 0) survey.pings.push_back(ping);
  }
  if (survey.pings.empty()) {
    throw std::runtime_error(files.front().string() + ": no ping with soundings within the position fixes (" +
                             std::to_string(track.size()) + " fixes)");
  }
  survey.metadata.crs = projection.crs();
  nlohmann::json summaries = nlohmann::json::array();
  for (const FileSummary& f : out.files) summaries.push_back(to_json(f));
  survey.metadata.sonar = {{"format", "XTF"}, {"files", summaries}};
  if (options.reference_nav) survey.reference_nav = read_reference_nav(*options.reference_nav);
  return out;
}

void stream_soundings(const std::vector<std::filesystem::path>& files, Survey& survey, PingSink& sink) {
  sink.begin(survey);
  const std::vector<NavSample>& nav = survey.nav;
  std::size_t next = 0, sample = 0;  // the survey's next ping, and the navigation sample of the last
  std::vector<Beam> beams;
  double last = -INFINITY;
  for (std::size_t f = 0; f < files.size(); ++f) {
    FileSource source(files[f]);
    Reader reader(source, files[f].string());
    const Geometry geometry = geometry_of(reader, files[f]);
    while (auto packet = reader.next()) {
      const auto* p = std::get_if<BathyPing>(&*packet);
      if (p == nullptr) continue;
      const std::string at = where(files[f], reader);
      const auto changed = [&] { return std::runtime_error(at + ": the file changed while it was read"); };
      check_order(p->time, last, at);
      if (nav.empty() || p->time < nav.front().time || p->time > nav.back().time) continue;
      while (sample < nav.size() && nav[sample].time < p->time) ++sample;
      // No sample at its time: a ping the first reading left out (an attitude dropout).
      if (sample == nav.size() || nav[sample].time != p->time) continue;
      beams.clear();
      append_soundings(*p, geometry, beams);
      if (beams.empty()) continue;
      if (next == survey.pings.size() || survey.pings[next].time != p->time || survey.pings[next].beam_count != beams.size()) {
        throw changed();
      }
      sink.ping(p->time, beams);
      ++next;
    }
  }
  if (next != survey.pings.size()) throw std::runtime_error(files.back().string() + ": the file changed while it was read");
  std::vector<Ping>().swap(survey.pings);
  std::vector<Beam>().swap(survey.beams);
}

std::optional<double> first_ping_time(const std::filesystem::path& path) {
  FileSource source(path);
  Reader reader(source, path.string());
  while (const auto packet = reader.next()) {
    if (const auto* ping = std::get_if<BathyPing>(&*packet)) return ping->time;
  }
  return std::nullopt;
}

bool is_xtf_path(const std::filesystem::path& path) {
  return has_extension(path, ".xtf");
}

}  // namespace bathyslam::xtf
