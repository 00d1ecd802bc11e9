#include "core/io/kongsberg/all_survey.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include <Eigen/Geometry>

#include "core/io/file_extension.h"
#include "core/io/kongsberg/all_datagrams.h"
#include "core/io/sonar_tracks.h"
#include "core/types/format.h"
#include "core/types/pose.h"

namespace bathyslam::kongsberg {
namespace {

// Dual-head and dual-swath sonars write each head's swaths of a few ping cycles one after the
// other (the EM2040 file in tests/data/all: head 2004's two pings, then head 2031's), so swaths
// come nearly, not exactly, in time order. Both readings put them in order through a window this
// many swaths wide; a file further out of order is refused.
constexpr std::size_t kOrderWindow = 64;
constexpr std::size_t kMaxKeptInstallationText = 4096;
constexpr std::size_t kMaxKeptProfiles = 20;  // as for GSF: metadata per survey is bounded

std::string utc(double seconds) { return format_utc(seconds, "%Y-%m-%dT%H:%M:%SZ"); }

// An XYZ 88 swath between the datagram and the survey.
struct Swath {
  double time = 0;
  int serial = 0;
  std::size_t file = 0;
  double heading_deg = 0, transducer_depth_m = 0;
  std::vector<DepthBeam> beams;  // empty when only counted
  std::uint32_t soundings = 0;   // valid beams
};

std::uint32_t valid_beams(const DepthPing& p) {
  return static_cast<std::uint32_t>(std::count_if(p.beams.begin(), p.beams.end(), [](const DepthBeam& b) { return b.valid(); }));
}

class TimeOrder {
 public:
  // `swath` in; the swaths now due (held beyond the window) appended to `due` in time order.
  void push(Swath swath, std::vector<Swath>& due, const std::string& where) {
    if (swath.time < last_) {
      throw std::runtime_error(where + ": swath at " + utc(swath.time) +
                               " comes more than " + std::to_string(kOrderWindow) +
                               " swaths after later ones; give the files in time order");
    }
    const std::pair<double, int> key{swath.time, swath.serial};
    held_.emplace(key, std::move(swath));
    if (held_.size() > kOrderWindow) pop(due);
  }
  void flush(std::vector<Swath>& due) {
    while (!held_.empty()) pop(due);
  }

 private:
  void pop(std::vector<Swath>& due) {
    auto first = held_.begin();
    last_ = first->second.time;
    due.push_back(std::move(first->second));
    held_.erase(first);
  }
  std::multimap<std::pair<double, int>, Swath> held_;
  double last_ = -std::numeric_limits<double>::infinity();
};

// The positioning system the sonar used in real time (descriptor bit 7); files that flag none: the
// lowest-numbered.
class ActiveSystem {
 public:
  explicit ActiveSystem(const std::vector<Position>& all) {
    any_active_ = std::any_of(all.begin(), all.end(), [](const Position& p) { return p.active; });
    for (const Position& p : all) lowest_ = std::min(lowest_, p.system);
  }
  bool uses(const Position& p) const { return any_active_ ? p.active : p.system == lowest_; }

 private:
  bool any_active_ = false;
  int lowest_ = 4;
};

GeodeticTrack track_of(const std::vector<Position>& all, const ActiveSystem& active) {
  std::vector<GeodeticFix> fixes;
  for (const Position& p : all) {
    if (active.uses(p)) fixes.push_back({p.time, p.latitude_deg, p.longitude_deg});
  }
  return GeodeticTrack(std::move(fixes));
}

// The swath's valid soundings in the vehicle frame of `nav` (its time's sample), appended to
// `beams`: level-frame beams turned back by the sample's roll and pitch, their depth taken from
// the sample's transducer depth (another head of the same ping may sit deeper).
void append_soundings(const Swath& s, const NavSample& nav, std::vector<Beam>& beams) {
  const Eigen::Matrix3d level_to_vehicle = vehicle_to_level_rotation(nav.roll_deg, nav.pitch_deg).transpose();
  const double below_sample = s.transducer_depth_m - nav.depth_m;
  for (std::size_t i = 0; i < s.beams.size(); ++i) {
    const DepthBeam& b = s.beams[i];
    if (!b.valid()) continue;
    const Eigen::Vector3d v = level_to_vehicle * Eigen::Vector3d(b.along_m, b.across_m, b.depth_m + below_sample);
    beams.push_back({static_cast<std::uint32_t>(i), static_cast<float>(v.x()), static_cast<float>(v.y()),
                     static_cast<float>(v.z())});
  }
}

Swath swath_of(DepthPing&& p, std::size_t file, bool keep_beams) {
  Swath s{p.time, p.serial, file, p.heading_deg, p.transducer_depth_m, {}, valid_beams(p)};
  if (keep_beams) s.beams = std::move(p.beams);
  return s;
}

class SummaryBuilder {
 public:
  explicit SummaryBuilder(std::string file) { s_.file = std::move(file); }
  void add(const Datagram& d) {
    if (const auto* p = std::get_if<DepthPing>(&d)) add_swath(*p);
    else if (const auto* f = std::get_if<Position>(&d)) add_fix(*f);
    else if (const auto* a = std::get_if<Attitude>(&d)) s_.attitude_samples += a->time.size();
    else if (std::holds_alternative<Installation>(d)) s_.installation = true;
    else if (std::holds_alternative<SoundSpeedProfile>(d)) ++s_.sound_speed_profiles;
    else ++s_.skipped_datagrams;
  }
  FileSummary finish(std::uint64_t bytes, std::uint64_t datagrams, int model) {
    s_.bytes = bytes;
    s_.datagrams = datagrams;
    s_.model = model;
    s_.heads.assign(heads_.begin(), heads_.end());
    return s_;
  }

 private:
  static void widen(bool first, double& lo, double& hi, double v) {
    lo = first ? v : std::min(lo, v);
    hi = first ? v : std::max(hi, v);
  }
  void add_swath(const DepthPing& p) {
    widen(s_.swaths == 0, s_.time_begin, s_.time_end, p.time);
    ++s_.swaths;
    heads_.insert(p.serial);
    s_.beams += p.beams.size();
    for (const DepthBeam& b : p.beams) {
      if (!b.valid()) {
        ++s_.rejected_beams;
        continue;
      }
      widen(s_.soundings == 0, s_.depth_min_m, s_.depth_max_m, b.depth_m + p.transducer_depth_m);
      ++s_.soundings;
    }
  }
  void add_fix(const Position& f) {
    widen(s_.positions == 0, s_.latitude_min, s_.latitude_max, f.latitude_deg);
    widen(s_.positions == 0, s_.longitude_min, s_.longitude_max, f.longitude_deg);
    ++s_.positions;
  }
  FileSummary s_;
  std::set<int> heads_;
};

std::string where(const std::filesystem::path& path, const Reader& reader) {
  return path.string() + ":" + std::to_string(reader.bytes_read());
}

}  // namespace

nlohmann::json to_json(const FileSummary& s) {
  return {{"file", s.file},
          {"format", "Kongsberg EM .all"},
          {"model", "EM" + std::to_string(s.model)},
          {"bytes", s.bytes},
          {"datagrams", s.datagrams},
          {"swaths", s.swaths},
          {"heads", s.heads},
          {"beams", s.beams},
          {"soundings", s.soundings},
          {"rejected_beams", s.rejected_beams},
          {"swaths_outside_navigation", s.swaths_outside_navigation},
          {"positions", s.positions},
          {"positions_used", s.positions_used},
          {"attitude_samples", s.attitude_samples},
          {"installation_parameters", s.installation},
          {"sound_speed_profiles", s.sound_speed_profiles},
          {"skipped_datagrams", s.skipped_datagrams},
          {"time_begin", utc(s.time_begin)},
          {"time_end", utc(s.time_end)},
          {"latitude_deg", {s.latitude_min, s.latitude_max}},
          {"longitude_deg", {s.longitude_min, s.longitude_max}},
          {"depth_m", {s.depth_min_m, s.depth_max_m}}};
}

std::string to_text(const FileSummary& s) {
  std::string heads;
  for (int h : s.heads) heads += (heads.empty() ? "" : ", ") + std::to_string(h);
  return format("%s: Kongsberg EM%d .all, %llu bytes, %llu datagrams\n", s.file.c_str(), s.model,
                static_cast<unsigned long long>(s.bytes), static_cast<unsigned long long>(s.datagrams)) +
         format("  swaths      %llu XYZ 88 from head(s) %s, %llu outside the position fixes\n",
                static_cast<unsigned long long>(s.swaths), heads.c_str(),
                static_cast<unsigned long long>(s.swaths_outside_navigation)) +
         format("  soundings   %llu of %llu beams (%llu rejected)\n", static_cast<unsigned long long>(s.soundings),
                static_cast<unsigned long long>(s.beams), static_cast<unsigned long long>(s.rejected_beams)) +
         format("  time        %s .. %s\n", utc(s.time_begin).c_str(),
                utc(s.time_end).c_str()) +
         format("  latitude    %.5f .. %.5f\n  longitude   %.5f .. %.5f\n", s.latitude_min, s.latitude_max,
                s.longitude_min, s.longitude_max) +
         format("  depth       %.1f .. %.1f m\n", s.depth_min_m, s.depth_max_m) +
         format("  navigation  %llu position fixes (%llu of the active system), %llu attitude samples\n",
                static_cast<unsigned long long>(s.positions), static_cast<unsigned long long>(s.positions_used),
                static_cast<unsigned long long>(s.attitude_samples)) +
         format("  metadata    installation parameters %s, %llu sound speed profiles, %llu other datagrams skipped\n",
                s.installation ? "yes" : "no", static_cast<unsigned long long>(s.sound_speed_profiles),
                static_cast<unsigned long long>(s.skipped_datagrams));
}

SurveyRead read_survey(const std::vector<std::filesystem::path>& files, const ReadOptions& options) {
  if (files.empty()) throw std::runtime_error("no .all file given");
  SurveyRead out;
  std::vector<Position> positions;
  std::vector<std::size_t> position_file;
  AttitudeTrack motion;
  std::string installation;
  nlohmann::json profiles = nlohmann::json::array();
  std::vector<Swath> swaths;
  TimeOrder order;
  for (std::size_t f = 0; f < files.size(); ++f) {
    FileSource source(files[f]);
    Reader reader(source, files[f].string());
    SummaryBuilder summary(files[f].filename().string());
    while (auto datagram = reader.next()) {
      summary.add(*datagram);
      if (auto* p = std::get_if<DepthPing>(&*datagram)) {
        order.push(swath_of(std::move(*p), f, options.keep_soundings), swaths, where(files[f], reader));
      } else if (const auto* fix = std::get_if<Position>(&*datagram)) {
        positions.push_back(*fix);
        position_file.push_back(f);
      } else if (const auto* a = std::get_if<Attitude>(&*datagram)) {
        for (std::size_t i = 0; i < a->time.size(); ++i) motion.add({a->time[i], a->roll_deg[i], a->pitch_deg[i]});
      } else if (const auto* i = std::get_if<Installation>(&*datagram); i && installation.empty()) {
        installation = i->text.substr(0, kMaxKeptInstallationText);
      } else if (const auto* svp = std::get_if<SoundSpeedProfile>(&*datagram); svp && profiles.size() < kMaxKeptProfiles) {
        nlohmann::json points = nlohmann::json::array();
        for (std::size_t k = 0; k < svp->depth_m.size(); ++k) points.push_back({svp->depth_m[k], svp->sound_speed_m_s[k]});
        profiles.push_back({{"taken", format("%08u %02u:%02u:%02u", svp->date, svp->time_ms / 3600000, svp->time_ms / 60000 % 60,
                                             svp->time_ms / 1000 % 60)},
                            {"depth_m_sound_speed_m_s", points}});
      }
    }
    out.files.push_back(summary.finish(reader.bytes_read(), reader.datagrams_read(), reader.model()));
  }
  order.flush(swaths);
  motion.sort();
  const ActiveSystem active(positions);
  const GeodeticTrack fixes = track_of(positions, active);
  for (std::size_t k = 0; k < positions.size(); ++k) out.files[position_file[k]].positions_used += active.uses(positions[k]);

  Survey& survey = out.survey;
  survey.metadata.name = files.front().stem().string();
  FixProjection projection(options.crs);
  for (Swath& s : swaths) {
    const auto fix = fixes.at(s.time);
    if (!fix) {
      ++out.files[s.file].swaths_outside_navigation;
      continue;
    }
    // Two heads of one ping share one navigation sample (the first head's transducer depth).
    if (survey.nav.empty() || s.time > survey.nav.back().time) {
      const auto [easting, northing] = projection.forward(fix->first, fix->second, files[s.file].string() + " at " + utc(s.time));
      const AttitudeSample motion_now = motion.at(s.time);
      survey.nav.push_back({s.time, easting, northing, s.transducer_depth_m, motion_now.roll_deg, motion_now.pitch_deg,
                            s.heading_deg});
    }
    Ping ping{s.time, static_cast<std::uint32_t>(survey.beams.size()), s.soundings};
    if (options.keep_soundings) {
      append_soundings(s, survey.nav.back(), survey.beams);
      ping.beam_count = static_cast<std::uint32_t>(survey.beams.size()) - ping.first_beam;
      std::vector<DepthBeam>().swap(s.beams);
    }
    if (ping.beam_count > 0) survey.pings.push_back(ping);
  }
  if (survey.pings.empty()) {
    throw std::runtime_error(files.front().string() + ": no swath with soundings within the position fixes (" +
                             std::to_string(fixes.size()) + " fixes of the active positioning system)");
  }
  survey.metadata.crs = projection.crs();
  nlohmann::json summaries = nlohmann::json::array();
  for (const FileSummary& f : out.files) summaries.push_back(to_json(f));
  survey.metadata.sonar = {{"format", "Kongsberg EM .all"},
                           {"files", summaries},
                           {"installation_parameters", installation},
                           {"sound_speed_profiles", profiles}};
  if (options.reference_nav) survey.reference_nav = read_reference_nav(*options.reference_nav);
  return out;
}

void stream_soundings(const std::vector<std::filesystem::path>& files, Survey& survey, PingSink& sink) {
  sink.begin(survey);
  const std::vector<NavSample>& nav = survey.nav;
  std::size_t next = 0, sample = 0;  // the survey's next ping, and the navigation sample of the last
  std::vector<Beam> beams;
  std::string at;  // where the last swath was read, for errors
  const auto changed = [&] { return std::runtime_error(at + ": the file changed while it was read"); };
  const auto hand_on = [&](std::vector<Swath>& due) {
    for (const Swath& s : due) {
      if (nav.empty() || s.time < nav.front().time || s.time > nav.back().time) continue;
      while (sample < nav.size() && nav[sample].time < s.time) ++sample;
      if (sample == nav.size() || nav[sample].time != s.time) throw changed();
      beams.clear();
      append_soundings(s, nav[sample], beams);
      if (beams.empty()) continue;
      if (next == survey.pings.size() || survey.pings[next].time != s.time || survey.pings[next].beam_count != beams.size()) {
        throw changed();
      }
      sink.ping(s.time, beams);
      ++next;
    }
    due.clear();
  };
  TimeOrder order;
  std::vector<Swath> due;
  for (std::size_t f = 0; f < files.size(); ++f) {
    FileSource source(files[f]);
    Reader reader(source, files[f].string());
    while (auto datagram = reader.next()) {
      auto* p = std::get_if<DepthPing>(&*datagram);
      if (p == nullptr) continue;
      at = where(files[f], reader);
      order.push(swath_of(std::move(*p), f, true), due, at);
      hand_on(due);
    }
  }
  order.flush(due);
  hand_on(due);
  if (next != survey.pings.size()) throw changed();
  std::vector<Ping>().swap(survey.pings);
  std::vector<Beam>().swap(survey.beams);
}

std::optional<double> first_swath_time(const std::filesystem::path& path) {
  FileSource source(path);
  Reader reader(source, path.string());
  while (const auto datagram = reader.next()) {
    if (const auto* swath = std::get_if<DepthPing>(&*datagram)) return swath->time;
  }
  return std::nullopt;
}

bool is_all_path(const std::filesystem::path& path) {
  return has_extension(path, ".all");
}

}  // namespace bathyslam::kongsberg
